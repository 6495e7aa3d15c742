// The client's errors are `#[non_exhaustive]`: a match outside the runtime needs a `_` arm, so
// that a new kind of error is not a breaking change for the application.
use drivemap_runtime::error::Error;

fn describe(e: &Error) -> &'static str {
    match e {
        Error::Timeout { .. } => "timeout",
        Error::Unsettled { .. } => "unsettled",
        Error::Exception { .. } => "exception",
        Error::Io { .. } => "io",
        Error::Link(_) => "link",
        Error::Refused(_) => "refused",
        Error::Value(_) => "value",
        Error::Overrun { .. } => "overrun",
    }
}

fn main() {
    let _ = describe;
}
