//! `include/sightline.h` is what cbindgen generates from `src/lib.rs` today
//! (`SIGHTLINE_BLESS=1 cargo test -p sightline-capi --test header` rewrites it).

#[test]
fn the_committed_header_is_up_to_date() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let config = cbindgen::Config::from_file(dir.join("cbindgen.toml")).unwrap();
    let mut generated = Vec::new();
    cbindgen::Builder::new()
        .with_config(config)
        .with_src(dir.join("src/lib.rs"))
        .generate()
        .expect("cbindgen reads src/lib.rs")
        .write(&mut generated);
    let path = dir.join("include/sightline.h");
    if std::env::var_os("SIGHTLINE_BLESS").is_some() {
        std::fs::write(&path, &generated).unwrap();
    }
    let committed = std::fs::read(&path).unwrap_or_default();
    assert!(
        committed == generated,
        "include/sightline.h is out of date: run SIGHTLINE_BLESS=1 cargo test -p sightline-capi --test header"
    );
}
