//! drivemap code generator
