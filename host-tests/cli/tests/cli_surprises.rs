//! The `pfe` CLI without surprises (issue 41): input with no scan is an error, outputs go only
//! into directories that exist, arguments outside what the help lists are refused at parse
//! time, the same kind of failure has the same exit code everywhere, a capture holds the scans
//! reported, nothing is written where the user did not say, and the help is plain text with
//! every option listed.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: a panic fails the test

#[path = "../../tests/common/mod.rs"]
mod common;
use std::path::Path;

use common::{arg, fixture, pfe, spawn_pfe, stderr, TempDir};

/// One line on stderr, exit 2, nothing on stdout, and the line names `name`.
fn assert_no_scan(args: &[&str], out: &std::process::Output, name: &str) {
    let e = stderr(out);
    assert_eq!(out.status.code(), Some(2), "{args:?}: {e}");
    assert!(out.stdout.is_empty(), "{args:?}");
    assert_eq!(e.trim_end().lines().count(), 1, "{args:?}: {e}");
    assert!(
        e.contains("no ") && e.contains(" found in "),
        "{args:?}: {e}"
    );
    assert!(e.contains(name), "{args:?}: {e}");
}

#[test]
fn input_with_no_scan_exits_2_naming_the_file() {
    let dir = TempDir::new("surprise-empty");
    let empty = dir.0.join("empty.txt");
    std::fs::write(&empty, "").unwrap();
    // A valid bag with no message at all.
    let bag = dir.0.join("empty.mcap");
    let mut buf = std::io::Cursor::new(Vec::new());
    common::mcap_writer(&mut buf, 4096).finish().unwrap();
    std::fs::write(&bag, buf.into_inner()).unwrap();
    let garbage = dir.0.join("garbage.mcap");
    std::fs::write(&garbage, "not a bag\n").unwrap();
    let e = arg(&empty);
    for (args, name) in [
        (
            vec!["extract", "--format", "carmen", "/dev/null"],
            "/dev/null",
        ),
        (vec!["extract", "--format", "csv", e], e),
        (vec!["extract", "--format", "hokuyo", e], e),
        (vec!["extract", "--format", "lms200", e], e),
        (vec!["decode", e], e),
        (vec!["decode", "/dev/null"], "/dev/null"),
        (
            vec![
                "plot",
                "--format",
                "csv",
                e,
                "--scan",
                "0",
                "-o",
                "/dev/null",
            ],
            e,
        ),
    ] {
        assert_no_scan(&args, &pfe(&args), name);
    }
    // An empty stdin is named as such.
    for args in [vec!["extract", "--format", "csv", "-"], vec!["decode", "-"]] {
        let child = spawn_pfe(&args);
        let out = child.wait_with_output().unwrap();
        assert_no_scan(&args, &out, "stdin");
    }
    // Bags: empty, not a bag, or no bytes at all (already exit 2; kept so).
    for b in [&bag, &garbage, &empty] {
        let out = pfe(&["extract", "--format", "mcap", arg(b)]);
        assert_eq!(out.status.code(), Some(2), "{b:?}: {}", stderr(&out));
        assert!(stderr(&out).contains(arg(b)), "{}", stderr(&out));
    }
    // realdata on an empty log: exit 2, the log named (already so).
    let out = pfe(&["realdata", e]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(stderr(&out).contains(e), "{}", stderr(&out));
}

/// The data sets of a `pfe bench --json` run.
fn bench_datasets(out: &std::process::Output) -> Vec<String> {
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    report["datasets"]
        .as_array()
        .unwrap()
        .iter()
        .map(|d| d["dataset"].as_str().unwrap().to_string())
        .collect()
}

#[test]
fn bench_reads_carmen_logs_only_from_carmen_dir() {
    let dir = TempDir::new("surprise-bench");
    // `../shared/data/carmen` as seen from `cwd`: no longer read unless named.
    let cwd = dir.0.join("cwd");
    let logs = dir.0.join("shared/data/carmen");
    std::fs::create_dir_all(&cwd).unwrap();
    std::fs::create_dir_all(&logs).unwrap();
    std::fs::copy(fixture("room.log"), logs.join("room.log")).unwrap();
    let bench = |extra: &[&str]| {
        std::process::Command::new(common::pfe_bin())
            .args([
                "bench",
                "--sim-scans",
                "1",
                "--reps",
                "1",
                "--json",
                "--report-only",
            ])
            .args(extra)
            .current_dir(&cwd)
            .output()
            .unwrap()
    };
    let out = bench(&[]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert_eq!(bench_datasets(&out), ["simulated", "interleaved"]);
    let out = bench(&["--carmen", arg(&logs)]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert_eq!(bench_datasets(&out), ["simulated", "interleaved", "carmen"]);
    // A directory with no log, one whose only log is empty, one that is absent: exit 2.
    let none = dir.0.join("none");
    std::fs::create_dir(&none).unwrap();
    let one = dir.0.join("one");
    std::fs::create_dir(&one).unwrap();
    std::fs::write(one.join("empty.log"), "").unwrap();
    for (d, says) in [
        (&none, "no scan found in"),
        (&one, "no scan found in"),
        (&dir.0.join("nope"), "no such directory"),
    ] {
        let out = bench(&["--carmen", arg(d)]);
        let e = stderr(&out);
        assert_eq!(out.status.code(), Some(2), "{d:?}: {e}");
        assert!(e.contains(says) && e.contains(arg(d)), "{e}");
        assert!(out.stdout.is_empty(), "{d:?}");
    }
    let help = pfe(&["bench", "--help"]);
    assert!(!String::from_utf8_lossy(&help.stdout).contains("shared/data"));
}

#[test]
fn sweeps_are_1_2_4_or_auto_at_parse_time() {
    let room = fixture("room.csv");
    let log = fixture("room.log");
    let (room, log) = (arg(&room), arg(&log));
    for n in ["0", "3", "5", "8", "x", ""] {
        for args in [
            vec!["extract", "--format", "csv", "--sweeps", n, room],
            vec![
                "plot", "--format", "csv", "--sweeps", n, room, "--scan", "1", "-o", "-",
            ],
            vec!["realdata", "--sweeps", n, log],
        ] {
            let out = pfe(&args);
            let e = stderr(&out);
            assert_eq!(out.status.code(), Some(2), "{args:?}: {e}");
            assert!(out.stdout.is_empty(), "{args:?}");
            // clap's own error, naming the allowed values.
            assert!(
                e.contains("possible values: auto, 1, 2, 4"),
                "{args:?}: {e}"
            );
        }
    }
    for n in ["auto", "1", "2", "4"] {
        let out = pfe(&["extract", "--format", "csv", "--sweeps", n, room]);
        assert!(out.status.success(), "{n}: {}", stderr(&out));
    }
}

#[test]
fn no_writer_creates_a_directory() {
    let dir = TempDir::new("surprise-dirs");
    let room = fixture("room.csv");
    let log = fixture("room.log");
    let (room, log) = (arg(&room), arg(&log));
    let gone = dir.0.join("gone");
    let file = |name: &str| gone.join("deeper").join(name);
    let (svg, html, sheet, mcap, md, lms) = (
        file("x.svg"),
        file("x.html"),
        file("sheet.svg"),
        file("x.mcap"),
        file("r.md"),
        file("x.lms"),
    );
    let deeper = arg(&gone.join("deeper")).to_string();
    for args in [
        vec![
            "plot",
            "--format",
            "csv",
            room,
            "--scan",
            "1",
            "-o",
            arg(&svg),
        ],
        vec![
            "plot",
            "--format",
            "csv",
            room,
            "--scan",
            "1",
            "-o",
            arg(&svg),
            "--force",
        ],
        vec![
            "plot",
            "--format",
            "csv",
            room,
            "--scans",
            "0..2",
            "--html",
            arg(&html),
        ],
        vec![
            "plot",
            "--format",
            "csv",
            room,
            "--scans",
            "0..2",
            "--sheet",
            arg(&sheet),
        ],
        vec!["extract", "--format", "csv", room, "--mcap", arg(&mcap)],
        vec!["listen", "--input", "/dev/null", "--mcap", arg(&mcap)],
        vec![
            "listen",
            "--input",
            "/dev/null",
            "--svg",
            arg(&gone.join("deeper")),
        ],
        vec!["bench", "--sim-scans", "1", "--reps", "1", "--md", arg(&md)],
        vec!["realdata", log, "--md", arg(&md)],
        vec!["eval", "--scans", "1", "--out", &deeper],
        vec!["record", "--port", "/dev/null", "-o", arg(&lms)],
    ] {
        let out = pfe(&args);
        let e = stderr(&out);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {e}");
        assert!(e.contains("no such directory"), "{args:?}: {e}");
        assert!(!gone.exists(), "{args:?} created {gone:?}");
    }
    // Into a directory that exists: written.
    let ok = dir.0.join("x.svg");
    let out = pfe(&[
        "plot",
        "--format",
        "csv",
        room,
        "--scan",
        "1",
        "-o",
        arg(&ok),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(ok.is_file());
}

#[test]
fn a_port_that_is_no_tty_exits_2_in_record_as_in_listen() {
    let dir = TempDir::new("surprise-port");
    let file = dir.0.join("not-a-tty");
    std::fs::write(&file, "").unwrap();
    let out = dir.0.join("x.lms");
    for port in ["/dev/null", arg(&file), "/nonexistent/tty"] {
        let listen = pfe(&["listen", "--port", port, "--seconds", "1"]);
        let record = pfe(&["record", "--port", port, "-o", arg(&out)]);
        assert_eq!(listen.status.code(), Some(2), "{port}: {}", stderr(&listen));
        assert_eq!(record.status.code(), Some(2), "{port}: {}", stderr(&record));
        assert!(stderr(&record).contains(port), "{}", stderr(&record));
        assert!(!out.exists());
    }
}

/// B0 telegrams (scans) in a raw LMS200 capture.
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
fn record_captures_exactly_the_scans_it_reports() {
    use std::time::{Duration, Instant};
    let dir = TempDir::new("surprise-record");
    let link = dir.0.join("lms");
    let mut emulator = spawn_pfe(&["emulate", "--pty", arg(&link), "--seconds", "120"]);
    let t0 = Instant::now();
    while link.symlink_metadata().is_err() {
        assert!(t0.elapsed() < Duration::from_secs(10), "no pty link");
        std::thread::sleep(Duration::from_millis(20));
    }
    for (k, n) in [1u64, 5, 12].into_iter().enumerate() {
        let out = dir.0.join(format!("take{k}.lms"));
        let scans = n.to_string();
        let r = pfe(&[
            "record",
            "--port",
            arg(&link),
            "--baud",
            "38400",
            "--scans",
            &scans,
            "-o",
            arg(&out),
        ]);
        assert!(r.status.success(), "{}", stderr(&r));
        let summary: serde_json::Value = serde_json::from_slice(&r.stdout).unwrap();
        let bytes = std::fs::read(&out).unwrap();
        assert_eq!(summary["scans"].as_u64(), Some(n), "{summary}");
        assert_eq!(summary["bytes"].as_u64(), Some(bytes.len() as u64));
        assert_eq!(b0_count(&bytes), n as usize, "--scans {n}");
        // What `pfe decode` reads from it agrees.
        let d = pfe(&["decode", arg(&out)]);
        assert_eq!(String::from_utf8_lossy(&d.stdout).lines().count() as u64, n);
    }
    // Ctrl-C: the emulator removes its link and exits 0.
    let int = std::process::Command::new("kill")
        .args(["-INT", &emulator.id().to_string()])
        .status()
        .unwrap();
    assert!(int.success());
    assert!(emulator.wait().unwrap().success());
}

#[test]
fn eval_writes_only_into_out() {
    let dir = TempDir::new("surprise-eval");
    let docs = dir.0.join("docs");
    std::fs::create_dir(&docs).unwrap();
    let eval = |extra: &[&str]| {
        std::process::Command::new(common::pfe_bin())
            .args(["eval", "--scans", "1", "--sweep", "1", "--passes", "1"])
            .args(extra)
            .current_dir(&dir.0)
            .output()
            .unwrap()
    };
    let listing = |d: &Path| {
        let mut names: Vec<String> = std::fs::read_dir(d)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        names
    };
    // Without --out: the tables on stdout, nothing written (the CWD's docs/ stays empty).
    let out = eval(&[]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(String::from_utf8_lossy(&out.stdout).contains("pfe-default"));
    assert!(listing(&docs).is_empty(), "{:?}", listing(&docs));
    assert_eq!(listing(&dir.0), ["docs"]);
    // --no-write (kept for scripts): the same tables.
    let quiet = eval(&["--no-write"]);
    assert!(quiet.status.success(), "{}", stderr(&quiet));
    assert!(listing(&docs).is_empty());
    // --out DIR: the report and its four plots there.
    let out = eval(&["--out", arg(&docs)]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert_eq!(
        listing(&docs),
        [
            "EVALUATION.md",
            "eval-errors.svg",
            "eval-ratios.svg",
            "eval-scenes.svg",
            "eval-time.svg"
        ]
    );
}

/// Every subcommand of `pfe` (as `pfe --help` lists them).
const SUBCOMMANDS: [&str; 11] = [
    "extract",
    "decode",
    "plot",
    "eval",
    "bench",
    "emulate",
    "record",
    "realdata",
    "listen",
    "completions",
    "man",
];

/// `pfe ARGS --help` (exit 0, on stdout).
fn help(args: &[&str]) -> String {
    let out = pfe(&[args, &["--help"]].concat());
    assert!(out.status.success(), "{args:?}: {}", stderr(&out));
    String::from_utf8(out.stdout).unwrap()
}

#[test]
fn help_is_plain_text() {
    let mut all = vec![help(&[])];
    for sub in SUBCOMMANDS {
        all.push(help(&[sub]));
    }
    for text in all {
        // Intra-doc links (`[`ros2`]`, `[Foo]`-style references) are rustdoc, not help.
        for rustdoc in ["[`", "`]", "](", "[crate::", "[super::", "[Self::"] {
            assert!(!text.contains(rustdoc), "{rustdoc:?} in:\n{text}");
        }
    }
}

#[test]
fn decode_lists_only_lms200() {
    let out = pfe(&["decode", "--help"]);
    let help = String::from_utf8_lossy(&out.stdout);
    assert!(help.contains("lms200"), "{help}");
    for other in ["csv", "carmen", "hokuyo", "mcap"] {
        assert!(!help.contains(other), "{other} in: {help}");
    }
    let out = pfe(&["decode", "--format", "csv", arg(&fixture("room.csv"))]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(stderr(&out).contains("lms200"), "{}", stderr(&out));
}

#[test]
fn eval_emulate_and_record_have_clap_help_with_every_option() {
    for (sub, options) in [
        (
            "eval",
            &[
                "--kind",
                "--scans",
                "--seed",
                "--sigma",
                "--sweep",
                "--passes",
                "--out",
                "--no-write",
                "--command",
                "--force",
            ][..],
        ),
        (
            "emulate",
            &[
                "--pty",
                "--tcp",
                "--scans",
                "--seconds",
                "--seed",
                "--baud",
                "--variant",
                "--unit",
                "--source",
                "--trace",
            ][..],
        ),
        (
            "record",
            &[
                "--port",
                "--output",
                "--scans",
                "--force",
                "--baud",
                "--variant",
                "--unit",
            ][..],
        ),
    ] {
        let text = help(&[sub]);
        assert!(text.contains(&format!("Usage: pfe {sub} ")), "{text}");
        let (_, section) = text.split_once("\nOptions:\n").expect("an options section");
        for o in options {
            // Each option on its own line, with words after it (its help).
            let line = section
                .lines()
                .find(|l| l.trim_start().starts_with(o) || l.contains(&format!(", {o}")))
                .unwrap_or_else(|| panic!("{sub}: no line for {o} in:\n{text}"));
            let words = line
                .split_whitespace()
                .filter(|w| w.chars().all(char::is_alphabetic));
            assert!(words.count() >= 2, "{sub} {o}: undocumented: {line:?}");
        }
    }
    // The defaults are shown where there are some, and stay what they were.
    let eval = help(&["eval"]);
    for d in [
        "[default: mixed]",
        "[default: 100]",
        "[default: 1,2,5,10]",
        "[default: 5]",
    ] {
        assert!(eval.contains(d), "{d} in:\n{eval}");
    }
    assert!(help(&["record"]).contains("[default: 10]"));
}

#[test]
fn bash_completion_names_every_subcommand() {
    let out = pfe(&["completions", "bash"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let script = String::from_utf8(out.stdout).unwrap();
    // The words offered after `pfe `: the first opts="-..." line of the script.
    let top = script
        .lines()
        .find(|l| l.trim_start().starts_with("opts=\"-"))
        .expect("an opts line");
    let words: Vec<&str> = top
        .trim()
        .trim_start_matches("opts=\"")
        .trim_end_matches('"')
        .split(' ')
        .collect();
    for sub in SUBCOMMANDS {
        assert!(words.contains(&sub), "{sub} not offered: {top}");
    }
    // Options of a subcommand are completed too.
    assert!(
        script.contains("--sweeps") && script.contains("--carmen"),
        "{script}"
    );
    // bash reads it (syntax check only).
    let dir = TempDir::new("surprise-bash");
    let file = dir.0.join("pfe.bash");
    std::fs::write(&file, &script).unwrap();
    let bash = std::process::Command::new("bash")
        .arg("-n")
        .arg(&file)
        .output();
    match bash {
        Ok(b) => assert!(b.status.success(), "{}", String::from_utf8_lossy(&b.stderr)),
        Err(e) => pfe_testkit::skip::skip(
            "cli_surprises::bash_completion_names_every_subcommand (bash -n)",
            &format!("no bash: {e}"),
            pfe_testkit::skip::Need::Optional,
        ),
    }
    for shell in ["zsh", "fish", "elvish", "powershell"] {
        let out = pfe(&["completions", shell]);
        assert!(out.status.success() && !out.stdout.is_empty(), "{shell}");
    }
    let out = pfe(&["completions", "tcsh"]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
}

#[test]
fn man_page_is_roff_and_lists_every_subcommand() {
    let out = pfe(&["man"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let page = String::from_utf8(out.stdout).unwrap();
    // The first request after the string definitions (.ie/.el, for the apostrophe) is .TH.
    let first = page
        .lines()
        .find(|l| !l.starts_with(".ie ") && !l.starts_with(".el "))
        .unwrap();
    assert!(first.starts_with(".TH pfe 1 "), "{first}");
    assert!(page.contains("\n.SH SUBCOMMANDS\n"), "{page}");
    for sub in SUBCOMMANDS {
        let entry = format!("pfe\\-{}(1)", sub.replace('-', "\\-"));
        assert!(page.contains(&entry), "{entry} not in:\n{page}");
    }
    // One subcommand's page: its options.
    let out = pfe(&["man", "extract"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let extract = String::from_utf8(out.stdout).unwrap();
    assert!(extract.contains(".TH pfe-extract 1 "), "{extract}");
    assert!(extract.contains("\\-\\-sweeps"), "{extract}");
    assert_eq!(pfe(&["man", "nonsense"]).status.code(), Some(2));
    // groff reads it without a warning, when it is installed.
    let dir = TempDir::new("surprise-man");
    for (name, text) in [("pfe.1", &page), ("pfe-extract.1", &extract)] {
        let file = dir.0.join(name);
        std::fs::write(&file, text).unwrap();
        match std::process::Command::new("groff")
            // -k: through preconv (UTF-8 input, as man(1) reads it).
            .args(["-k", "-man", "-Tutf8", "-z", "-ww"])
            .arg(&file)
            .output()
        {
            Ok(g) => {
                assert!(g.status.success(), "{}", String::from_utf8_lossy(&g.stderr));
                assert!(
                    g.stderr.is_empty(),
                    "{name}: {}",
                    String::from_utf8_lossy(&g.stderr)
                );
            }
            Err(e) => pfe_testkit::skip::skip(
                "cli_surprises::man_page_is_roff_and_lists_every_subcommand (groff)",
                &format!("no groff: {e}"),
                pfe_testkit::skip::Need::Optional,
            ),
        }
    }
}
