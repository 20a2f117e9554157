//! Every `unsafe` operation of the crate is in `src/ffi_ptr.rs`: the other modules allow the
//! `unsafe_code` lint only for `#[unsafe(no_mangle)]` (exported names must be unique), so this
//! test keeps them free of unsafe blocks, functions, impls and traits.

#[test]
fn unsafe_code_lives_in_ffi_ptr_alone() {
    let src = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut checked = 0;
    for entry in std::fs::read_dir(src).unwrap() {
        let path = entry.unwrap().path();
        if path.file_name().unwrap() == "ffi_ptr.rs" {
            continue;
        }
        let text = std::fs::read_to_string(&path).unwrap();
        for (n, line) in text.lines().enumerate() {
            let code = line.split("//").next().unwrap();
            let words: Vec<&str> = code.split_whitespace().collect();
            for pair in words.windows(2) {
                let bad = pair[0].ends_with("unsafe")
                    && (pair[1].starts_with('{') || ["fn", "impl", "trait"].contains(&pair[1]));
                assert!(
                    !bad,
                    "{}:{}: unsafe outside ffi_ptr.rs: {line}",
                    path.display(),
                    n + 1
                );
            }
            assert!(
                !code.contains("unsafe{"),
                "{}:{}: {line}",
                path.display(),
                n + 1
            );
        }
        checked += 1;
    }
    assert!(checked >= 6);
}
