//! Pose benchmark on the shared CARMEN logs: registers every pair of consecutive scans without
//! a prior and compares with the logs' corrected poses ([`pfe_eval::posebench`], which reads
//! the logs with pfe-formats' CARMEN reader; `pfe posebench` and `cargo xtask pose` run the
//! same).
//!
//! ```text
//! cargo run --release -p pfe-pose --example carmen_bench [-- [--max-pairs N] [--odometry] [LOG.log.gz ...]]
//! ```
//!
//! Without logs named, every CARMEN log in `../shared/data/carmen` (beside the checkout) is
//! read; when that folder is absent it says so loudly and exits with status 0 (nothing to
//! measure).

use std::path::{Path, PathBuf};

use pfe_eval::posebench;

fn main() {
    let mut max_pairs = usize::MAX;
    let mut odometry = false;
    let mut logs: Vec<PathBuf> = Vec::new();
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--max-pairs" => {
                max_pairs = args
                    .next()
                    .and_then(|v| v.parse().ok())
                    .unwrap_or(usize::MAX)
            }
            "--odometry" => odometry = true,
            _ => logs.push(PathBuf::from(a)),
        }
    }
    if logs.is_empty() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/data/carmen");
        match posebench::logs_in(&dir) {
            Some(found) => logs = found,
            None => {
                eprintln!(
                    "SKIPPED: no CARMEN logs at {} (the shared data folder is absent): nothing measured",
                    dir.display()
                );
                return;
            }
        }
    }
    let mut rows = Vec::new();
    for log in &logs {
        match posebench::run_log(log, max_pairs, odometry) {
            Ok(st) => rows.push((posebench::log_name(log), st)),
            Err(e) => eprintln!("{e:#}"),
        }
    }
    print!("{}", posebench::table(&rows, odometry));
}
