//! Replays, without libFuzzer, every committed regression input (`fuzz/regressions/<target>/`)
//! and freshly generated seeds through the fuzz targets' bodies: a fixed crash stays fixed.
use std::path::{Path, PathBuf};

fn replay(dir: &Path) -> usize {
    let mut n = 0;
    for target in ["lms_decoder", "extractor", "readers", "frame_decoder"] {
        let Ok(entries) = std::fs::read_dir(dir.join(target)) else {
            continue;
        };
        for e in entries.flatten() {
            let data = std::fs::read(e.path()).unwrap();
            eprintln!("{target}: {}", e.path().display());
            match target {
                "lms_decoder" => drop(pfe_fuzz_harness::lms_decoder(&data)),
                "extractor" => drop(pfe_fuzz_harness::extractor(&data)),
                "readers" => drop(pfe_fuzz_harness::readers(&data)),
                _ => drop(pfe_fuzz_harness::frame_decoder(&data)),
            }
            n += 1;
        }
    }
    n
}

fn fuzz_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

#[test]
fn committed_regressions_pass() {
    let n = replay(&fuzz_dir().join("regressions"));
    eprintln!("{n} regression inputs replayed");
}

#[test]
fn generated_seeds_pass_and_decode() {
    let shared = fuzz_dir().join("../../shared");
    if !shared.join("docs").is_dir() {
        skip(
            "fuzz harness generated_seeds_pass_and_decode",
            &format!("{} is absent", shared.display()),
        );
        return;
    }
    let out = std::env::temp_dir().join(format!("pfe-seeds-{}", std::process::id()));
    let files = pfe_fuzz_harness::seeds::generate(&out, &shared).unwrap();
    assert!(files >= 20, "{files} seed files");
    assert_eq!(replay(&out), files);
    // The protocol vectors decode as telegrams.
    let vectors = pfe_fuzz_harness::seeds::protocol_vectors(&shared.join("docs")).unwrap();
    assert_eq!(vectors.len(), 21);
    for v in &vectors {
        // Device telegrams (address 0x80) decode; host commands (0x00) are not for the host.
        let want = usize::from(v[1] == 0x80);
        let got = pfe_fuzz_harness::lms_decoder(&[&[0u8, 0][..], v].concat());
        assert_eq!(got, want, "{v:02x?}");
    }
    std::fs::remove_dir_all(&out).ok();
}

/// A copy of `host_tests::skip::skip` (this is a separate workspace): prints the skip, lists it
/// in `$PFE_SKIPS_FILE` (else `../../target/pfe-skips.txt`) for `cargo xtask test`'s summary,
/// and fails under `CI=true` (CI has `../shared`).
fn skip(test: &str, reason: &str) {
    use std::io::Write;
    eprintln!("SKIPPED: {test}: {reason}");
    let file = std::env::var_os("PFE_SKIPS_FILE")
        .map(PathBuf::from)
        .unwrap_or_else(|| fuzz_dir().join("../target/pfe-skips.txt"));
    let _ = std::fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(&file)
        .and_then(|mut f| writeln!(f, "{test}: {reason}"));
    if std::env::var("CI").is_ok_and(|v| v == "true" || v == "1") {
        panic!("{test}: {reason}; CI provides this, so skipping it is a failure");
    }
}
