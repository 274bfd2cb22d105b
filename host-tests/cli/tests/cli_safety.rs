//! The `pfe` CLI never loses a user's data and never prints nonsense without an error: the
//! emulator's pty link, `record`'s output file, argument and input validation, exit codes.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: a panic fails the test

use std::path::Path;
use std::process::{Command, Output};
use std::time::{Duration, Instant};

#[path = "../../tests/common/mod.rs"]
mod common;
use common::{arg, fixture, pfe, scratch, spawn_pfe, stderr};

/// Waits until `path` exists (as a link or a file), at most 10 s.
fn wait_for(path: &Path) {
    let t0 = Instant::now();
    while path.symlink_metadata().is_err() {
        assert!(
            t0.elapsed() < Duration::from_secs(10),
            "{} never appeared",
            path.display()
        );
        std::thread::sleep(Duration::from_millis(20));
    }
}

fn interrupt(child: &std::process::Child) {
    let ok = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(ok.success());
}

/// `pfe emulate --pty PTY --seconds SECONDS`.
fn emulate(pty: &Path, seconds: &str) -> Output {
    pfe(&["emulate", "--pty", arg(pty), "--seconds", seconds])
}

#[test]
fn emulate_refuses_to_replace_a_file_at_its_pty_path() {
    let dir = scratch("emu-file");
    let path = dir.join("notes.txt");
    std::fs::write(&path, "a user's notes").unwrap();
    let out = emulate(&path, "0.2");
    assert!(!out.status.success(), "{}", stderr(&out));
    assert!(stderr(&out).contains("not replacing"), "{}", stderr(&out));
    assert_eq!(std::fs::read_to_string(&path).unwrap(), "a user's notes");
    // Nor a link to something else, nor a directory.
    let link = dir.join("link");
    std::os::unix::fs::symlink(&path, &link).unwrap();
    let out = emulate(&link, "0.2");
    assert!(!out.status.success());
    assert_eq!(std::fs::read_link(&link).unwrap(), path);
    let out = emulate(&dir, "0.2");
    assert!(!out.status.success());
    assert!(dir.is_dir());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn emulate_replaces_its_stale_link_and_removes_its_link_on_exit() {
    let dir = scratch("emu-stale");
    let link = dir.join("lms");
    std::os::unix::fs::symlink("/dev/pts/987654", &link).unwrap();
    let out = emulate(&link, "0.3");
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(link.symlink_metadata().is_err(), "link left behind");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn emulate_removes_its_link_on_ctrl_c() {
    let dir = scratch("emu-int");
    let link = dir.join("lms");
    let child = spawn_pfe(&["emulate", "--pty", arg(&link), "--seconds", "60"]);
    wait_for(&link);
    assert!(std::fs::read_link(&link).unwrap().starts_with("/dev/pts/"));
    let t0 = Instant::now();
    interrupt(&child);
    let out = child.wait_with_output().unwrap();
    assert!(t0.elapsed() < Duration::from_secs(10));
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(
        link.symlink_metadata().is_err(),
        "link left behind after Ctrl-C"
    );
    let summary: serde_json::Value =
        serde_json::from_slice(&out.stdout).expect("a JSON summary on Ctrl-C");
    assert!(summary["scans_sent"].is_u64());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn record_never_empties_an_existing_file() {
    let dir = scratch("rec-exists");
    let out = dir.join("take1.lms");
    std::fs::write(&out, b"a user's recording").unwrap();
    let o = arg(&out);
    // Without --force: refused as bad input before the port is touched.
    let r = pfe(&["record", "--port", "/nonexistent/tty", "-o", o]);
    assert_eq!(r.status.code(), Some(2), "{}", stderr(&r));
    assert!(stderr(&r).contains("--force"), "{}", stderr(&r));
    // With --force but a port that cannot be opened: the file is untouched.
    let r = pfe(&["record", "--port", "/nonexistent/tty", "-o", o, "--force"]);
    assert_eq!(r.status.code(), Some(2), "{}", stderr(&r));
    assert!(stderr(&r).contains("/nonexistent/tty"), "{}", stderr(&r));
    assert_eq!(std::fs::read(&out).unwrap(), b"a user's recording");
    // A port that is not a tty: the same.
    let r = pfe(&["record", "--port", "/dev/null", "-o", o, "--force"]);
    assert_eq!(r.status.code(), Some(2), "{}", stderr(&r));
    assert_eq!(std::fs::read(&out).unwrap(), b"a user's recording");
    assert_eq!(
        std::fs::read_dir(&dir).unwrap().count(),
        1,
        "no temporary left"
    );
    let r = pfe(&["record", "--help"]);
    assert!(String::from_utf8_lossy(&r.stdout).contains("--force"));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// B0 telegrams in a raw capture.
fn b0_count(bytes: &[u8]) -> usize {
    use lms2xx::codec::frame::{Decoder, Event, MAX_TELEGRAM};
    let mut dec = Decoder::<MAX_TELEGRAM>::new();
    let (mut rest, mut n) = (bytes, 0);
    loop {
        let (u, ev) = dec.feed(rest);
        rest = &rest[u..];
        match ev {
            Some(Event::Telegram(t)) if t.payload().first() == Some(&0xB0) => n += 1,
            Some(_) => {}
            None => return n,
        }
    }
}

#[test]
fn record_interrupted_keeps_what_it_had() {
    use common::PtyServer;
    use lms200_emulator::serve::Pty;
    use lms200_emulator::{Emulator, EmulatorConfig};

    let dir = scratch("rec-int");
    let link = dir.join("lms");
    let out = dir.join("capture.lms");
    let pty = Pty::open(&link).unwrap();
    let emu = PtyServer::start(pty, Emulator::from_config(EmulatorConfig::default()));
    let (link, out_arg) = (arg(&link), arg(&out));
    let record = [
        "record", "--port", link, "--baud", "38400", "--scans", "1000000",
    ];
    let child = spawn_pfe(&[&record[..], &["-o", out_arg]].concat());
    // Wait until the temporary capture holds a few scans (361 words each: ~730 bytes).
    let t0 = Instant::now();
    loop {
        let part: u64 = std::fs::read_dir(&dir)
            .unwrap()
            .filter_map(|e| e.ok())
            .filter(|e| e.file_name().to_string_lossy().contains(".part-"))
            .filter_map(|e| e.metadata().ok())
            .map(|m| m.len())
            .sum();
        if part > 4000 {
            break;
        }
        assert!(t0.elapsed() < Duration::from_secs(30), "no capture growing");
        std::thread::sleep(Duration::from_millis(20));
    }
    assert!(!out.exists(), "the output appears only at the end");
    interrupt(&child);
    let r = child.wait_with_output().unwrap();
    let _ = emu.stop();
    assert_eq!(r.status.code(), Some(130), "{}", stderr(&r));
    assert!(stderr(&r).contains("interrupted"), "{}", stderr(&r));
    let bytes = std::fs::read(&out).expect("the capture is kept");
    assert!(b0_count(&bytes) >= 2, "{} scans kept", b0_count(&bytes));
    let summary: serde_json::Value = serde_json::from_slice(&r.stdout).unwrap();
    assert_eq!(summary["bytes"].as_u64(), Some(bytes.len() as u64));
    assert_eq!(summary["interrupted"], true);
    let left: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .filter_map(|e| e.ok())
        .map(|e| e.file_name())
        .filter(|n| n.to_string_lossy().contains(".part-"))
        .collect();
    assert!(left.is_empty(), "temporary left: {left:?}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn sigma_r_must_be_a_positive_finite_noise() {
    let room = fixture("room.csv");
    let file = arg(&room);
    let dir = scratch("sigma");
    let svg = dir.join("p.svg");
    for bad in ["0", "-5", "NaN", "inf", "-inf", "5mm"] {
        let sigma = format!("--sigma-r={bad}");
        let plot = ["plot", "--format", "csv", &sigma, file, "--scan", "1", "-o"];
        for args in [
            vec!["extract", "--format", "csv", &sigma, file],
            [&plot[..], &[arg(&svg)]].concat(),
        ] {
            let out = pfe(&args);
            assert_eq!(out.status.code(), Some(2), "{args:?}: {}", stderr(&out));
            assert!(stderr(&out).contains("--sigma-r"), "{}", stderr(&out));
            assert!(out.stdout.is_empty());
            assert!(!svg.exists());
        }
    }
    // The same arguments with a good σ_r work (so the failures above are σ_r's).
    let plot = [
        "plot",
        "--format",
        "csv",
        "--sigma-r=0.5",
        file,
        "--scan",
        "1",
        "-o",
    ];
    let out = pfe(&plot);
    assert_eq!(out.status.code(), Some(2), "-o needs a value");
    let out = pfe(&[&plot[..], &[arg(&svg)]].concat());
    assert!(out.status.success(), "{}", stderr(&out));
    std::fs::remove_dir_all(&dir).unwrap();
    let out = pfe(&["extract", "--format", "csv", "--sigma-r", "0.5", arg(&room)]);
    assert!(out.status.success(), "{}", stderr(&out));
}

#[test]
fn input_with_no_scan_is_an_error_with_a_hint() {
    let room = fixture("room.csv");
    let capture = fixture("lms200-good.bin");
    let (room, capture) = (arg(&room), arg(&capture));
    for (args, hint) in [
        (
            vec!["extract", "--format", "carmen", room],
            "try --format csv",
        ),
        (
            vec!["extract", "--format", "lms200", room],
            "try --format csv",
        ),
        (
            vec!["extract", "--format", "hokuyo", room],
            "try --format csv",
        ),
        (
            vec!["extract", "--format", "csv", capture],
            "try --format lms200",
        ),
        (
            vec![
                "plot",
                "--format",
                "lms200",
                room,
                "--scan",
                "1",
                "-o",
                "/dev/null",
            ],
            "csv",
        ),
        (
            vec!["decode", "--format", "lms200", room],
            "pfe extract --format csv",
        ),
    ] {
        let out = pfe(&args);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {}", stderr(&out));
        assert!(stderr(&out).contains(hint), "{args:?}: {}", stderr(&out));
        assert!(out.stdout.is_empty(), "{args:?}");
    }
    // Garbage that no format reads: still an error, with the list of formats.
    let dir = scratch("noscan");
    let junk = dir.join("junk.bin");
    std::fs::write(
        &junk,
        (0..4000u32)
            .map(|i| (i * 7 % 251) as u8 | 0x80)
            .collect::<Vec<_>>(),
    )
    .unwrap();
    let out = pfe(&["extract", "--format", "lms200", arg(&junk)]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(stderr(&out).contains("no scan found"), "{}", stderr(&out));
    assert!(stderr(&out).contains("--format"), "{}", stderr(&out));
    // Empty input is bad input too: no scan in it (cli_surprises checks every reader).
    let empty = dir.join("empty.csv");
    std::fs::write(&empty, "").unwrap();
    let out = pfe(&["extract", "--format", "csv", arg(&empty)]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn an_error_quotes_at_most_80_characters_of_the_bad_field() {
    let dir = scratch("quote");
    let long = "x".repeat(100_000);
    for (format, text) in [
        ("csv", format!("1,-90,1,1000,{long}\n")),
        ("csv", format!("1,-90,{long},1000\n")),
        (
            "hokuyo",
            format!("/scan 0 -1.5 0.01 0.02 5.0 2 1.0 -{long}\n"),
        ),
        (
            "hokuyo",
            format!("/scan 0 -1.5 0.01 0.02 5.0 1 1.0 {long}\n"),
        ),
        (
            "carmen",
            format!("FLASER 3 1.0 {long} 1.0 0 0 0 0 0 0 0 h 0\n"),
        ),
    ] {
        let path = dir.join("long.txt");
        std::fs::write(&path, text).unwrap();
        let out = pfe(&["extract", "--format", format, arg(&path)]);
        assert_eq!(out.status.code(), Some(2), "{format}: {}", stderr(&out));
        let e = stderr(&out);
        assert!(
            e.len() < 300,
            "{format}: {} characters: {}",
            e.len(),
            &e[..300]
        );
        assert!(e.contains(&format!("{}…", "x".repeat(79))), "{format}: {e}");
        assert!(!e.contains(&"x".repeat(81)), "{format}: {e}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn every_subcommand_exits_2_on_bad_arguments() {
    for args in [
        vec!["extract", "--bogus"],
        vec!["decode"],
        vec!["plot", "--format", "csv"],
        vec!["eval", "--scans", "x"],
        vec!["eval", "--kind", "nowhere"],
        vec!["eval", "--sweep", "1,x", "--no-write"],
        vec!["eval", "--scans", "0", "--no-write"],
        vec!["bench", "--reps", "-1"],
        vec!["emulate", "--baud", "1234", "--tcp", "127.0.0.1:0"],
        vec!["emulate", "--seconds", "0.1"],
        vec!["record", "--scans", "x"],
        vec!["record", "--port", "/dev/null"],
        vec!["nonsense"],
    ] {
        let out = pfe(&args);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {}", stderr(&out));
        assert!(!stderr(&out).is_empty(), "{args:?}");
    }
    let help = pfe(&["--help"]);
    let text = String::from_utf8_lossy(&help.stdout);
    assert!(text.contains("Exit codes (every subcommand)"), "{text}");
    assert!(
        text.contains("2 bad input") && text.contains("1 any other"),
        "{text}"
    );
}

#[test]
fn bench_carmen_must_be_a_directory() {
    let room = fixture("room.log");
    let out = pfe(&["bench", "--carmen", arg(&room), "--sim-scans", "1"]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(stderr(&out).contains("not a directory"), "{}", stderr(&out));
}

#[test]
fn plot_to_stdout() {
    let room = fixture("room.csv");
    let out = pfe(&[
        "plot",
        "--format",
        "csv",
        arg(&room),
        "--scan",
        "1",
        "-o",
        "-",
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let svg = String::from_utf8(out.stdout).unwrap();
    assert!(
        svg.starts_with("<svg") || svg.starts_with("<?xml"),
        "{}",
        &svg[..40]
    );
    assert!(svg.trim_end().ends_with("</svg>"));
    assert!(!Path::new("-").exists(), "wrote a file named -");
}

#[test]
fn decode_needs_no_format() {
    let path = fixture("lms200-good.bin");
    let implicit = pfe(&["decode", arg(&path)]);
    assert!(implicit.status.success(), "{}", stderr(&implicit));
    let explicit = pfe(&["decode", "--format", "lms200", arg(&path)]);
    assert_eq!(implicit.stdout, explicit.stdout);
    assert_eq!(String::from_utf8_lossy(&implicit.stdout).lines().count(), 3);
    let out = pfe(&["decode", fixture("room.csv").to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    let err = stderr(&out);
    assert!(err.contains("pfe extract --format csv"), "{err}");
}

#[test]
fn csv_nan_ranges_are_discontinuities() {
    let dir = scratch("csv-nan");
    // A wall at x = 2000 mm seen from −30° to +30° in 1° steps, broken by NaN at beam 30.
    let ranges = |gap: &str| -> String {
        (0..61)
            .map(|i| {
                if i == 30 {
                    gap.to_string()
                } else {
                    let b = f64::from(i - 30).to_radians();
                    format!("{:.1}", 2000.0 / b.cos())
                }
            })
            .collect::<Vec<_>>()
            .join(",")
    };
    let nan = dir.join("nan.csv");
    std::fs::write(
        &nan,
        format!("1,-30,1,{}\n2,-30,1,{}\n", ranges("NaN"), ranges("nan")),
    )
    .unwrap();
    let zero = dir.join("zero.csv");
    std::fs::write(
        &zero,
        format!("1,-30,1,{}\n2,-30,1,{}\n", ranges("0"), ranges("0")),
    )
    .unwrap();
    let a = pfe(&["extract", "--format", "csv", arg(&nan)]);
    assert!(a.status.success(), "{}", stderr(&a));
    let b = pfe(&["extract", "--format", "csv", arg(&zero)]);
    assert!(b.status.success(), "{}", stderr(&b));
    assert_eq!(a.stdout, b.stdout, "NaN reads as no return (like 0)");
    let first: serde_json::Value =
        serde_json::from_str(String::from_utf8_lossy(&a.stdout).lines().next().unwrap()).unwrap();
    let marks: Vec<u64> = common::u64s(&first["marks"]);
    assert!(
        marks.contains(&29) && marks.contains(&31),
        "the gap splits the wall: {marks:?}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn csv_beams_over_a_full_turn_are_rejected() {
    let dir = scratch("csv-turn");
    let path = dir.join("turn.csv");
    let ok = format!("1,-180,1{}\n", ",1000".repeat(361));
    let bad = format!("2,-180,1{}\n", ",1000".repeat(362));
    std::fs::write(&path, format!("{ok}{bad}")).unwrap();
    let out = pfe(&["extract", "--format", "csv", arg(&path)]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(stderr(&out).contains("line 2"), "{}", stderr(&out));
    assert!(stderr(&out).contains("full turn"), "{}", stderr(&out));
    assert_eq!(String::from_utf8_lossy(&out.stdout).lines().count(), 1);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_skip_is_listed_and_fails_in_ci() {
    let dir = scratch("skips");
    let file = dir.join("skips.txt");
    // The helper run in a child process (this test binary, one test), with its own skips file.
    let run = |ci: &str| {
        Command::new(std::env::current_exe().unwrap())
            .args([
                "--exact",
                "skip_helper_child",
                "--nocapture",
                "--include-ignored",
            ])
            .env("PFE_SKIPS_FILE", &file)
            .env("CI", ci)
            .output()
            .unwrap()
    };
    let out = run("false");
    assert!(out.status.success(), "{}", stderr(&out));
    let err = stderr(&out);
    assert!(err.contains("SKIPPED: demo_test: no widget"), "{err}");
    let listed = std::fs::read_to_string(&file).unwrap();
    assert_eq!(
        listed,
        "optional_test: local choice\ndemo_test: no widget\n"
    );
    let out = run("true");
    assert!(
        !out.status.success(),
        "a CI skip of what CI installs must fail"
    );
    let all = format!("{}{}", String::from_utf8_lossy(&out.stdout), stderr(&out));
    assert!(all.contains("CI provides this"), "{all}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Run only by `a_skip_is_listed_and_fails_in_ci`.
#[test]
#[ignore = "a child of a_skip_is_listed_and_fails_in_ci"]
fn skip_helper_child() {
    use pfe_testkit::skip::{skip, Need};
    skip("optional_test", "local choice", Need::Optional);
    skip("demo_test", "no widget", Need::InCi);
}

#[test]
fn report_and_plot_commands_never_replace_a_users_file() {
    let dir = scratch("reports");
    let read = |p: &Path| std::fs::read_to_string(p).unwrap();
    let room = fixture("room.csv");
    let plot = |out: &Path, force: bool| {
        let mut args = vec!["plot", "--format", "csv", arg(&room), "--scan", "1", "-o"];
        args.push(arg(out));
        if force {
            args.push("--force");
        }
        pfe(&args)
    };
    // A user's file: refused with exit 2 and left as it was.
    let mine = dir.join("figure.svg");
    std::fs::write(&mine, "<svg>my figure</svg>").unwrap();
    let out = plot(&mine, false);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(stderr(&out).contains("--force"), "{}", stderr(&out));
    assert!(stderr(&out).contains(arg(&mine)), "{}", stderr(&out));
    assert_eq!(read(&mine), "<svg>my figure</svg>");
    // pfe's own output is replaced by the next run; a user's file with --force.
    let ours = dir.join("plot.svg");
    for _ in 0..2 {
        let out = plot(&ours, false);
        assert!(out.status.success(), "{}", stderr(&out));
    }
    assert!(read(&ours).trim_end().ends_with("</svg>"));
    assert!(plot(&mine, true).status.success());
    assert!(!read(&mine).contains("my figure"));
    // Reports are checked before they run, their plots next to them too: nothing written.
    let theirs = dir.join("realdata-nis.svg");
    std::fs::write(&theirs, "my plot").unwrap();
    let md = dir.join("report.md");
    let out = pfe(&["realdata", arg(&fixture("room.log")), "--md", arg(&md)]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(stderr(&out).contains(arg(&theirs)), "{}", stderr(&out));
    assert!(!md.exists());
    assert_eq!(read(&theirs), "my plot");
    std::fs::write(dir.join("eval-time.svg"), "my timings").unwrap();
    let out = pfe(&["eval", "--scans", "1", "--out", arg(&dir)]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(!dir.join("EVALUATION.md").exists());
    let notes = dir.join("notes.md");
    std::fs::write(&notes, "# my notes\n").unwrap();
    let out = pfe(&["bench", "--sim-scans", "1", "--md", arg(&notes)]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert_eq!(read(&notes), "# my notes\n");
    assert!(!dir.join("perf-scaling.svg").exists());
    // A directory is never written, even with --force.
    let out = plot(&dir, true);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(dir.is_dir());
    std::fs::remove_dir_all(&dir).unwrap();
}
