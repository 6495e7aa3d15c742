// The drive's status is `#[non_exhaustive]`: it gains a field when a map gains a status role, so
// an application reads its fields (or starts from `Status::default()`) and cannot build it whole.
use drivemap_runtime::vfd::Status;

fn main() {
    let _ = Status {
        running: Some(true),
        reversing: None,
        fault: None,
        alarm: None,
        ready: None,
        zero_speed: None,
        speed_agree: None,
        accelerating: None,
        decelerating: None,
        stopping: None,
        drive_mode: None,
    };
}
