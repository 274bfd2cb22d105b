//! `cargo xtask bench-mcu [--scans N | --worst]`: instruction counts of the firmware pipeline
//! with everything on (the host's extraction) on QEMU mps2-an386 with `-icount shift=10`
//! (SysTick-measured; instruction counts, not cycles), stage by stage (pfe-core's `probe`
//! feature, in the bench firmware only), on three sets of N scans (still at 0.5°, moving at
//! 0.5° with the sweeps out of place, moving at 0.25°), for pfe-core with libm and with
//! micromath; refreshes docs/PERFORMANCE.md and fails when the whole pipeline needs more than
//! 200 instructions per point (median, in any set). `--worst`: the adversarial scans instead,
//! the maximum per scan kind beside the algorithmic bound; fails above 1 000 000 instructions
//! per scan.
//!
//! Steps: simulated scans → B0 telegrams (`demo_host bench-scans`), built into the
//! `pfe-bench` firmware (`PFE_BENCH_SCANS`), run under QEMU, timing frames decoded and
//! tabulated (`demo_host bench`).

use anyhow::{Context, Result};

use crate::fw::{build_fw, demo_host, target_dir, write_section_titled};
use crate::util;

/// Runs the command.
pub fn run(args: &[String]) -> Result<()> {
    let scans = match args {
        [] => "100".to_string(),
        [flag, n] if flag == "--scans" => n.clone(),
        [flag] if flag == "--worst" => return worst(),
        _ => anyhow::bail!("usage: cargo xtask bench-mcu [--scans N | --worst]"),
    };
    util::ensure_target()?;
    util::ensure_apt("qemu-system-arm", "qemu-system-arm")?;
    let base = target_dir().join("bench-mcu");
    std::fs::create_dir_all(&base).context("creating the bench directory")?;
    let scans_file = base.join("scans.bin");
    demo_host(&[
        "bench-scans".as_ref(),
        "--scans".as_ref(),
        scans.as_ref(),
        "--out".as_ref(),
        scans_file.as_os_str(),
    ])?;
    let md = util::root().join("docs").join("PERFORMANCE.md");
    write_section_titled(
        &md,
        "math-accuracy",
        "libm vs micromath: accuracy",
        "bench-mcu",
        &accuracy()?,
    )?;
    let env = [("PFE_BENCH_SCANS", scans_file.as_os_str())];
    // With pfe-core's step probe: the per-stage rows.
    let libm = build_fw("pfe-bench", &["probe"], &env, &base.join("libm"))?;
    let mm = build_fw(
        "pfe-bench",
        &["micromath", "probe"],
        &env,
        &base.join("micromath"),
    )?;
    demo_host(&[
        "bench".as_ref(),
        "--scans".as_ref(),
        scans.as_ref(),
        "--elf".as_ref(),
        libm.as_os_str(),
        "--elf-micromath".as_ref(),
        mm.as_os_str(),
        "--md".as_ref(),
        md.as_os_str(),
    ])
}

/// `--worst`: the adversarial scans built into `pfe-bench` (libm), measured and tabulated.
fn worst() -> Result<()> {
    util::ensure_target()?;
    util::ensure_apt("qemu-system-arm", "qemu-system-arm")?;
    let base = target_dir().join("bench-mcu");
    std::fs::create_dir_all(&base).context("creating the bench directory")?;
    let (scans_file, kinds) = (base.join("worst.bin"), base.join("worst.txt"));
    demo_host(&[
        "worst-scans".as_ref(),
        "--out".as_ref(),
        scans_file.as_os_str(),
        "--kinds".as_ref(),
        kinds.as_os_str(),
    ])?;
    let env = [("PFE_BENCH_SCANS", scans_file.as_os_str())];
    // The libm build's directory: only the bench binary rebuilds.
    let elf = build_fw("pfe-bench", &["probe"], &env, &base.join("libm"))?;
    let md = util::root().join("docs").join("PERFORMANCE.md");
    demo_host(&[
        "worst".as_ref(),
        "--elf".as_ref(),
        elf.as_os_str(),
        "--kinds".as_ref(),
        kinds.as_os_str(),
        "--md".as_ref(),
        md.as_os_str(),
    ])
}

/// Accuracy of pfe-core with libm and with micromath: the `score` example (100 simulated mixed
/// scans, σ_r = 5 mm, seed 1) built each way; a Markdown table.
fn accuracy() -> Result<String> {
    let mut rows = String::new();
    for (math, features) in [("libm", None), ("micromath", Some("pfe-core/micromath"))] {
        let mut c = util::host_example("score");
        if let Some(f) = features {
            c.args(["--features", f]);
        }
        c.args([
            "--", "--kind", "mixed", "--scans", "100", "--sigma", "5", "--seed", "1",
        ]);
        eprintln!("$ {c:?}");
        let out = c.output().context("running the score example")?;
        anyhow::ensure!(
            out.status.success(),
            "score example ({math}) failed: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        for line in String::from_utf8_lossy(&out.stdout).lines() {
            let f: Vec<&str> = line.split_whitespace().collect();
            if let [method @ ("pfe-paper" | "pfe-default"), _us, fmr, fir, missed, spur, _matched, rho, alpha, ctr, r] =
                f.as_slice()
            {
                rows.push_str(&format!(
                    "| {method} | {math} | {fmr} | {fir} | {missed} | {spur} | {rho} | {alpha} | {ctr} | {r} |\n"
                ));
            }
        }
    }
    anyhow::ensure!(!rows.is_empty(), "no score rows parsed");
    Ok(format!(
        "Accuracy with `libm` (the default: libm's atan2, and pfe-core's own f32 sine and \
         cosine, within 2·10⁻⁷) and `micromath` (fast approximations of atan2, sin, cos; \
         a correctly rounded square root in both) on the host: the `score` example, 100 \
         simulated mixed scans, σ_r = 5 mm, seed 1 (`cargo run --release -p host-tests \
         --example score [--features pfe-core/micromath]`). Errors are medians over correctly \
         typed matched features.\n\n\
         | config | maths | FalseMarkRatio | FalseIdenRatio | missed | spurious | \\|Δρ\\| mm | \\|Δα\\| mrad | centre mm | \\|ΔR\\| mm |\n\
         |---|---|---:|---:|---:|---:|---:|---:|---:|---:|\n{rows}\n\
         libm stays the default: micromath saves instructions only where the paper's \
         threshold calls atan2 for every point (the speed table), costs accuracy (its atan2 \
         and sin/cos are approximations: larger line and circle errors and more false marks \
         above), and with libm the firmware's features are bit-identical to the host's (the \
         end-to-end checks rely on it).\n"
    ))
}
