//! Writes the golden blobs of `fixtures/golden/` again from `aprt_tests::golden`'s models:
//! run when the golden models change (`cargo run -p aprt-tests --release --example
//! write_golden`), then `tests/tests/golden.rs` checks what was written.

use aprt_tests::golden::{encode, golden_dir, golden_models};

fn main() -> std::io::Result<()> {
    for golden in golden_models() {
        let path = golden_dir().join(golden.0);
        std::fs::write(&path, encode(&golden))?;
        println!("wrote {}", path.display());
    }
    Ok(())
}
