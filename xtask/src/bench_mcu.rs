//! `cargo xtask bench-mcu [--scans N | --worst]`: instruction counts of the firmware pipeline
//! with everything on (the host's extraction) on QEMU mps2-an386 with `-icount shift=10`
//! (SysTick-measured; instruction counts, not cycles), stage by stage (pfe-core's
//! `Extractor::extract_observed`, in the bench firmware only), on three sets of N scans (still at 0.5°, moving at
//! 0.5° with the sweeps out of place, moving at 0.25°), for pfe-core with libm and with
//! micromath; refreshes docs/PERFORMANCE.md and fails when the whole pipeline needs more than
//! 200 instructions per point (median, in any set). `--worst`: the adversarial scans instead,
//! the maximum per scan kind beside the algorithmic bound; fails above 1 000 000 instructions
//! per scan.
//!
//! The pose step (also `--pose` alone): `pfe-bench-pose` on consecutive scans of a moving
//! robot (a simulated drive around a room, and the shared CARMEN csail log's LMS200 scans when
//! `../shared/data` is there, else skipped loudly), the pose step alone and the whole pipeline
//! with it, median and worst case per scan; fails when the pose step's median is above 500 000
//! instructions a scan, the pipeline's worst case above 1 500 000, or static RAM + stack above
//! 48 KiB (section `bench-mcu-pose` of docs/PERFORMANCE.md).
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
        [flag] if flag == "--pose" => return pose(),
        _ => anyhow::bail!("usage: cargo xtask bench-mcu [--scans N | --worst | --pose]"),
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
    // The per-stage rows: pfe-core's stage observer.
    let libm = build_fw("pfe-bench", &[], &env, &base.join("libm"))?;
    let mm = build_fw("pfe-bench", &["micromath"], &env, &base.join("micromath"))?;
    let extraction = demo_host(&[
        "bench".as_ref(),
        "--scans".as_ref(),
        scans.as_ref(),
        "--elf".as_ref(),
        libm.as_os_str(),
        "--elf-micromath".as_ref(),
        mm.as_os_str(),
        "--md".as_ref(),
        md.as_os_str(),
    ]);
    let pose = pose();
    extraction.and(pose)
}

/// The pose step: `pfe-bench-pose` on a simulated drive and, when the shared data is there,
/// the csail log's LMS200 scans; tabulated and held to the budgets (`demo_host pose-bench`).
fn pose() -> Result<()> {
    util::ensure_target()?;
    util::ensure_apt("qemu-system-arm", "qemu-system-arm")?;
    let base = target_dir().join("bench-mcu");
    std::fs::create_dir_all(&base).context("creating the bench directory")?;
    let (scans_file, kinds) = (base.join("pose.bin"), base.join("pose.txt"));
    let mut args: Vec<std::ffi::OsString> = vec![
        "pose-scans".into(),
        "--out".into(),
        scans_file.clone().into(),
        "--kinds".into(),
        kinds.clone().into(),
    ];
    // The csail log: an LMS200 at 180°/0.5° in mm (361 beams), as the board would get it.
    match util::shared_carmen_logs("bench-mcu (pose, real scans)")? {
        Some(logs) => match logs.iter().find(|l| l.contains("csail")) {
            Some(log) => {
                args.push("--carmen".into());
                args.push(util::root().join(log).into());
            }
            None => eprintln!("bench-mcu: SKIPPED the real scans of the pose bench: no csail log"),
        },
        None => eprintln!("bench-mcu: the pose bench on the simulated drive only"),
    }
    let resets = demo_host_output(&args)?;
    let resets = resets.trim().to_string();
    let env = [
        ("PFE_BENCH_SCANS", scans_file.as_os_str()),
        ("PFE_BENCH_RESET_AT", resets.as_ref()),
    ];
    let elf = build_fw("pfe-bench-pose", &[], &env, &base.join("pose"))?;
    let tool = util::llvm_tool("llvm-size")?;
    let (_, static_ram, _, _) = crate::size::sizes(&tool, &elf)?;
    let md = util::root().join("docs").join("PERFORMANCE.md");
    let ram = static_ram.to_string();
    demo_host(&[
        "pose-bench".as_ref(),
        "--elf".as_ref(),
        elf.as_os_str(),
        "--kinds".as_ref(),
        kinds.as_os_str(),
        "--scans".as_ref(),
        scans_file.as_os_str(),
        "--static-ram".as_ref(),
        ram.as_ref(),
        "--md".as_ref(),
        md.as_os_str(),
    ])
}

/// Runs `demo_host` with `args` and returns its stdout.
fn demo_host_output(args: &[std::ffi::OsString]) -> Result<String> {
    let mut c = util::cargo();
    c.args([
        "run",
        "--quiet",
        "-p",
        "host-tests",
        "--example",
        "demo_host",
        "--",
    ])
    .args(args);
    eprintln!("$ {c:?}");
    let out = c
        .stderr(std::process::Stdio::inherit())
        .output()
        .context("running demo_host")?;
    anyhow::ensure!(out.status.success(), "demo_host failed: {}", out.status);
    Ok(String::from_utf8_lossy(&out.stdout).into_owned())
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
    let elf = build_fw("pfe-bench", &[], &env, &base.join("libm"))?;
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
