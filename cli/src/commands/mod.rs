pub mod check;
pub mod diff;
pub mod doc;
pub mod export;
pub mod poll;
pub mod read;
pub mod write;
