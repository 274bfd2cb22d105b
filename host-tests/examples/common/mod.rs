//! What the real-data examples share: their command line (one CARMEN log and options with a
//! value each) and the walk over a log's pairs of scans.
// Each example uses what it needs of it.
#![allow(dead_code)]

use std::collections::BTreeMap;

use anyhow::{bail, Context, Result};
use pfe_eval::methods::{Extraction, Method};
use pfe_eval::realdata::{log_scans, LogScan, Seen};
use pfe_formats::Record;

/// A real-data example's command line: `NAME LOG [OPTION VALUE]…`.
pub struct LogArgs {
    /// The CARMEN log.
    pub log: String,
    /// The options given, by name (with their dashes).
    values: BTreeMap<&'static str, String>,
}

impl LogArgs {
    /// Parses the process's arguments for the example `name` taking `options`; `None` after
    /// printing the usage for `-h` / `--help`.
    pub fn parse(name: &str, options: &[&'static str]) -> Result<Option<Self>> {
        let usage = format!(
            "{name} LOG{}",
            options
                .iter()
                .map(|o| format!(" [{o} VALUE]"))
                .collect::<String>()
        );
        let (mut log, mut values) = (None, BTreeMap::new());
        let mut it = std::env::args().skip(1);
        while let Some(a) = it.next() {
            if a == "-h" || a == "--help" {
                println!("{usage}");
                return Ok(None);
            }
            if let Some(&o) = options.iter().find(|&&o| o == a) {
                values.insert(o, it.next().with_context(|| format!("{o} needs a value"))?);
            } else if log.is_none() && !a.starts_with('-') {
                log = Some(a);
            } else {
                bail!("unknown argument `{a}` (usage: {usage})");
            }
        }
        let log = log.with_context(|| format!("give a CARMEN log with poses (usage: {usage})"))?;
        Ok(Some(Self { log, values }))
    }

    /// The value of `option` parsed, or `default` when not given.
    pub fn get<T: std::str::FromStr>(&self, option: &str, default: T) -> Result<T>
    where
        T::Err: std::error::Error + Send + Sync + 'static,
    {
        match self.values.get(option) {
            Some(v) => v.parse().with_context(|| format!("{option} {v}")),
            None => Ok(default),
        }
    }
}

/// Runs `methods` over every scan of the CARMEN log `log` and calls `pair(m, a, b)` for every
/// pair of consecutive scans with poses, `a` and `b` what method `m` saw in them. Fails when
/// the log has fewer than two scans.
pub fn for_each_pair(
    log: &str,
    methods: &mut [Box<dyn Method>],
    mut pair: impl FnMut(usize, &Seen, &Seen),
) -> Result<()> {
    for_each_pair_with(log, methods, |_, _| (), |m, a, b| pair(m, &a.0, &b.0))
}

/// [`for_each_pair`] with what `keep(record, extraction)` takes from each scan beside what a
/// method saw in it.
pub fn for_each_pair_with<T>(
    log: &str,
    methods: &mut [Box<dyn Method>],
    mut keep: impl FnMut(&Record, &Extraction) -> T,
    mut pair: impl FnMut(usize, &(Seen, T), &(Seen, T)),
) -> Result<()> {
    let mut prev: Vec<Option<(Seen, T)>> = methods.iter().map(|_| None).collect();
    let mut scans = 0usize;
    for scan in log_scans(std::path::Path::new(log))? {
        let LogScan {
            record,
            context,
            pose,
        } = scan?;
        for (m, (method, prev)) in methods.iter_mut().zip(&mut prev).enumerate() {
            let ex = method.extract_in(&record.geometry, &record.ranges_mm, &context);
            let seen = pose.map(|p| (Seen::new(p, &ex.features), keep(&record, &ex)));
            if let (Some(a), Some(b)) = (prev.as_ref(), seen.as_ref()) {
                pair(m, a, b);
            }
            *prev = seen;
        }
        scans += 1;
    }
    if scans < 2 {
        bail!("{log}: fewer than two scans with poses");
    }
    Ok(())
}
