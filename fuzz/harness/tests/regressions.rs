//! Replays, without libFuzzer, every committed regression input (`fuzz/regressions/<target>/`),
//! the committed minimised campaign corpora (`fuzz/corpus-min/<target>/`) and freshly generated
//! seeds through the fuzz targets' bodies: a fixed crash stays fixed, and what the campaign
//! reached is re-checked on every run.
use std::path::{Path, PathBuf};

/// The fuzz targets (as `xtask::fuzz::TARGETS`).
const TARGETS: [&str; 5] = [
    "lms_decoder",
    "extractor",
    "readers",
    "frame_decoder",
    "lms_driver",
];

/// Runs one input through a target's body (its assertions are the checks).
fn run_target(target: &str, data: &[u8]) {
    match target {
        "lms_decoder" => drop(pfe_fuzz_harness::lms_decoder(data)),
        "extractor" => drop(pfe_fuzz_harness::extractor(data)),
        "readers" => drop(pfe_fuzz_harness::readers(data)),
        "frame_decoder" => drop(pfe_fuzz_harness::frame_decoder(data)),
        "lms_driver" => drop(pfe_fuzz_harness::lms_driver(data)),
        other => panic!("unknown fuzz target {other}"),
    }
}

/// Replays every file of `dir/<target>/` for each target; returns the count per target.
/// A missing directory counts 0.
fn replay(dir: &Path) -> Vec<(&'static str, usize)> {
    TARGETS
        .iter()
        .map(|&target| {
            let mut n = 0;
            if let Ok(entries) = std::fs::read_dir(dir.join(target)) {
                let mut paths: Vec<PathBuf> = entries.flatten().map(|e| e.path()).collect();
                paths.sort();
                for p in paths.iter().filter(|p| p.is_file()) {
                    let data = std::fs::read(p).unwrap();
                    eprintln!("{target}: {}", p.display());
                    run_target(target, &data);
                    n += 1;
                }
            }
            (target, n)
        })
        .collect()
}

/// Targets without a single input in `counts`.
fn empty_targets(counts: &[(&'static str, usize)]) -> Vec<&'static str> {
    counts.iter().filter(|c| c.1 == 0).map(|c| c.0).collect()
}

fn fuzz_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// Every target has committed inputs (at least its minimized seeds; fixed crashes are added by
/// `cargo xtask fuzz`'s instructions) and every one of them passes the target's checks.
#[test]
fn committed_regressions_pass() {
    let counts = replay(&fuzz_dir().join("regressions"));
    eprintln!("regression inputs replayed: {counts:?}");
    let empty = empty_targets(&counts);
    assert!(
        empty.is_empty(),
        "fuzz/regressions/<target>/ is missing or empty for {empty:?}: commit at least one input each"
    );
}

/// Every target has a committed minimised corpus (`cargo +nightly fuzz cmin` of a campaign, see
/// docs/TESTING.md) and every input of it passes the target's checks.
#[test]
fn committed_minimised_corpora_pass() {
    let counts = replay(&fuzz_dir().join("corpus-min"));
    eprintln!("minimised corpus inputs replayed: {counts:?}");
    let empty = empty_targets(&counts);
    assert!(
        empty.is_empty(),
        "fuzz/corpus-min/<target>/ is missing or empty for {empty:?}: commit the minimised corpus of each"
    );
}

/// The replay counts a target with no directory as empty (so the test above fails for it).
#[test]
fn a_missing_regressions_directory_is_empty() {
    let dir = std::env::temp_dir().join(format!("pfe-regr-{}", std::process::id()));
    std::fs::create_dir_all(dir.join("readers")).unwrap();
    std::fs::write(dir.join("readers/one"), b"\x001,2,3\n").unwrap();
    let counts = replay(&dir);
    std::fs::remove_dir_all(&dir).ok();
    assert_eq!(
        empty_targets(&counts),
        ["lms_decoder", "extractor", "frame_decoder", "lms_driver"]
    );
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
    let replayed: usize = replay(&out).iter().map(|c| c.1).sum();
    assert_eq!(replayed, files);
    // Each real log's scans as the newer CARMEN logger writes them read as its FLASER lines do.
    let mut newer = 0;
    for e in std::fs::read_dir(out.join("readers")).unwrap().flatten() {
        let name = e.file_name().to_string_lossy().into_owned();
        let Some(flaser) = name.strip_suffix(".robotlaser1") else {
            continue;
        };
        let read = |f: &str| {
            pfe_fuzz_harness::readers(&std::fs::read(out.join("readers").join(f)).unwrap())
        };
        let n = read(&name);
        assert!(n > 0 && n == read(flaser), "{name}: {n}");
        newer += 1;
    }
    let logs = std::fs::read_dir(shared.join("data/carmen")).map_or(0, |d| d.count());
    assert!(newer > 0 && newer == logs, "{newer} of {logs} CARMEN logs");
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

/// A copy of `pfe_testkit::skip::skip` (this is a separate workspace): prints the skip, lists it
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

/// The async driver target takes the `lms_driver` target's inputs (same layout): every
/// committed `lms_driver` regression and minimised-corpus input, and the emulator seeds, run
/// through it, where the async and the blocking driver must agree call by call. The emulator
/// sessions deliver scans, so the agreement covers streaming, not only failures.
#[test]
fn lms_driver_inputs_pass_through_the_async_driver() {
    let mut n = 0;
    for dir in ["regressions", "corpus-min"] {
        let Ok(entries) = std::fs::read_dir(fuzz_dir().join(dir).join("lms_driver")) else {
            continue;
        };
        for p in entries.flatten().map(|e| e.path()).filter(|p| p.is_file()) {
            pfe_fuzz_harness::lms_driver_async(&std::fs::read(&p).unwrap());
            n += 1;
        }
    }
    assert!(n > 0, "no committed lms_driver inputs");
    for (name, bytes) in pfe_fuzz_harness::lms_driver::seeds(&[]) {
        let scans = pfe_fuzz_harness::lms_driver_async(&bytes);
        if name.starts_with("emulator") {
            assert!(scans > 0, "{name}: no scan");
        }
    }
}
