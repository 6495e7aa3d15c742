// The value type of a read-only bit-field register has getters only: nothing builds a word that
// could not be written anyway.
use custom_drive::mini_drive as md;

fn main() {
    let _ = md::StatusBits::new().with_running(true);
}
