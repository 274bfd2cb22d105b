//! The committed C header is the one cbindgen generates from the code: a change to the C API
//! that is not regenerated fails here (regenerate with `PFE_BLESS_HEADER=1 cargo test -p
//! pfe-capi --test header`).

// Test helpers: a failure to run a tool or read a file fails the test.
#![allow(clippy::expect_used, clippy::panic, clippy::indexing_slicing)]

use std::path::Path;

#[test]
fn committed_header_matches_the_code() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"));
    let config = cbindgen::Config::from_file(dir.join("cbindgen.toml")).expect("cbindgen.toml");
    let bindings = cbindgen::Builder::new()
        .with_crate(dir)
        .with_config(config)
        .generate()
        .expect("cbindgen generates the header");
    let mut generated = Vec::new();
    bindings.write(&mut generated);
    let generated = String::from_utf8(generated).expect("UTF-8 header");
    let path = dir.join("include/pfe.h");
    if std::env::var_os("PFE_BLESS_HEADER").is_some() {
        std::fs::write(&path, &generated).expect("write include/pfe.h");
    }
    let committed = std::fs::read_to_string(&path).unwrap_or_default();
    if committed != generated {
        let line = committed
            .lines()
            .zip(generated.lines())
            .position(|(a, b)| a != b)
            .map_or(
                committed.lines().count().min(generated.lines().count()),
                |i| i,
            );
        panic!(
            "include/pfe.h differs from what cbindgen generates from the code (first at line {}):\n\
             committed: {:?}\ngenerated: {:?}\n\
             regenerate: PFE_BLESS_HEADER=1 cargo test -p pfe-capi --test header",
            line + 1,
            committed.lines().nth(line),
            generated.lines().nth(line)
        );
    }
}

/// The header states the capacities and sizes the library was built with.
#[test]
fn header_constants_are_the_code_constants() {
    let h = include_str!("../include/pfe.h");
    for (name, value) in [
        ("PFE_EXTRACTOR_SIZE", pfe_capi::PFE_EXTRACTOR_SIZE),
        ("PFE_EXTRACTOR_ALIGN", pfe_capi::PFE_EXTRACTOR_ALIGN),
        ("PFE_MAX_READINGS", pfe_capi::PFE_MAX_READINGS),
        ("PFE_MAX_FEATURES", pfe_capi::PFE_MAX_FEATURES),
    ] {
        assert!(
            h.contains(&format!("#define {name} {value}")),
            "{name} {value} not in pfe.h"
        );
    }
    assert!(pfe_capi::pfe_extractor_size() <= pfe_capi::PFE_EXTRACTOR_SIZE);
}
