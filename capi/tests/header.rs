//! The checked-in header, `include/aprt.h`, equals what cbindgen generates from the sources,
//! so the C ABI and its header never drift. `APRT_BLESS=1` rewrites it.

use std::path::Path;

#[test]
fn header_matches_the_sources() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"));
    let config = cbindgen::Config::from_file(dir.join("cbindgen.toml")).expect("cbindgen.toml");
    let mut generated = Vec::new();
    cbindgen::Builder::new()
        .with_crate(dir)
        .with_config(config)
        .generate()
        .expect("cbindgen generates the header")
        .write(&mut generated);
    let generated = String::from_utf8(generated).expect("the header is UTF-8");
    let path = dir.join("include/aprt.h");
    if std::env::var_os("APRT_BLESS").is_some() {
        std::fs::write(&path, &generated).expect("write include/aprt.h");
        return;
    }
    let checked_in = std::fs::read_to_string(&path).unwrap_or_default();
    if checked_in != generated {
        let line = checked_in
            .lines()
            .zip(generated.lines())
            .position(|(a, b)| a != b)
            .map_or(
                checked_in.lines().count().min(generated.lines().count()),
                |i| i,
            );
        panic!(
            "capi/include/aprt.h differs from what cbindgen generates (first at line {}); \
             regenerate it with `APRT_BLESS=1 cargo test --release -p aprt-capi --test header` \
             and commit it",
            line + 1
        );
    }
}
