//! The `pfe` CLI never loses a user's data and never prints nonsense without an error: the
//! emulator's pty link, `record`'s output file, argument and input validation, exit codes.

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

fn pfe(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_pfe"))
        .args(args)
        .output()
        .unwrap()
}

/// A fresh directory for one test.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("pfe-safety-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

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

#[test]
fn emulate_refuses_to_replace_a_file_at_its_pty_path() {
    let dir = scratch("emu-file");
    let path = dir.join("notes.txt");
    std::fs::write(&path, "a user's notes").unwrap();
    let out = pfe(&[
        "emulate",
        "--pty",
        path.to_str().unwrap(),
        "--seconds",
        "0.2",
    ]);
    assert!(!out.status.success(), "{}", stderr(&out));
    assert!(stderr(&out).contains("not replacing"), "{}", stderr(&out));
    assert_eq!(std::fs::read_to_string(&path).unwrap(), "a user's notes");
    // Nor a link to something else, nor a directory.
    let link = dir.join("link");
    std::os::unix::fs::symlink(&path, &link).unwrap();
    let out = pfe(&[
        "emulate",
        "--pty",
        link.to_str().unwrap(),
        "--seconds",
        "0.2",
    ]);
    assert!(!out.status.success());
    assert_eq!(std::fs::read_link(&link).unwrap(), path);
    let out = pfe(&[
        "emulate",
        "--pty",
        dir.to_str().unwrap(),
        "--seconds",
        "0.2",
    ]);
    assert!(!out.status.success());
    assert!(dir.is_dir());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn emulate_replaces_its_stale_link_and_removes_its_link_on_exit() {
    let dir = scratch("emu-stale");
    let link = dir.join("lms");
    std::os::unix::fs::symlink("/dev/pts/987654", &link).unwrap();
    let out = pfe(&[
        "emulate",
        "--pty",
        link.to_str().unwrap(),
        "--seconds",
        "0.3",
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(link.symlink_metadata().is_err(), "link left behind");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn emulate_removes_its_link_on_ctrl_c() {
    let dir = scratch("emu-int");
    let link = dir.join("lms");
    let child = Command::new(env!("CARGO_BIN_EXE_pfe"))
        .args([
            "emulate",
            "--pty",
            link.to_str().unwrap(),
            "--seconds",
            "60",
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
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
