//! Per recording, what a consumer can use of `pfe extract`'s output (issue 39): lines seen at
//! more than 85° incidence from the scanner at their midpoint, lines shorter than 10 mm, and
//! the share of small objects (runs of ≥ 3 returns, a jump ≥ 0.3 m or no return on both sides,
//! ≤ 0.3 m across) some feature covers (`pfe_eval::realdata::visible`).
//!
//! `cargo run -p host-tests --release --example visibility -- FORMAT LOG JSONL`
//!
//! JSONL: `pfe extract --format FORMAT LOG`'s output. Prints
//! one line: scans, lines, lines > 85°, lines < 10 mm, small objects, covered %, and the
//! objects and veil points the JSON reports (0 before the object feature).

use std::io::BufRead;

use anyhow::{bail, Context, Result};
use pfe_eval::realdata::visible::{incidence_deg, Seen, Visibility};
use pfe_formats::Format;

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [format, log, jsonl] = args.as_slice() else {
        bail!("usage: visibility FORMAT LOG JSONL");
    };
    let format = match format.as_str() {
        "carmen" => Format::Carmen,
        "hokuyo" => Format::Hokuyo,
        "csv" => Format::Csv,
        f => bail!("format {f}: carmen, hokuyo or csv"),
    };
    let input = pfe_formats::open_for(std::path::Path::new(log), format, |r| r)
        .with_context(|| format!("opening {log}"))?;
    let json = std::io::BufReader::new(
        std::fs::File::open(jsonl).with_context(|| format!("opening {jsonl}"))?,
    );
    let mut lines = json.lines();
    let mut v = Visibility::default();
    let (mut objects, mut veils) = (0usize, 0usize);
    for record in pfe_formats::scans(format, input) {
        let record = record.map_err(|e| anyhow::anyhow!("{log}: {e}"))?;
        let Some(line) = lines.next() else {
            bail!("{jsonl} ends before {log}")
        };
        let scan: serde_json::Value = serde_json::from_str(&line?)?;
        let num = |f: &serde_json::Value, k: &str| f[k].as_f64().unwrap_or(f64::NAN) as f32;
        let mut seen = Vec::new();
        for f in scan["features"].as_array().into_iter().flatten() {
            let first = f["first"].as_u64().unwrap_or(0) as usize;
            let last = f["last"].as_u64().unwrap_or(0) as usize;
            let line = match f["kind"].as_str() {
                Some("line") => {
                    let xy = |k: &str| {
                        let a = &f[k];
                        [
                            a[0].as_f64().unwrap_or(f64::NAN) as f32,
                            a[1].as_f64().unwrap_or(f64::NAN) as f32,
                        ]
                    };
                    let (s, e) = (xy("start"), xy("end"));
                    Some((
                        incidence_deg(num(f, "alpha"), s, e),
                        (e[0] - s[0]).hypot(e[1] - s[1]),
                    ))
                }
                Some("object") => {
                    objects += 1;
                    None
                }
                _ => None,
            };
            seen.push(Seen { first, last, line });
        }
        veils += scan["veils"].as_array().map_or(0, Vec::len);
        v.add(&record.geometry, &record.ranges_mm, &seen);
    }
    println!(
        "scans {} lines {} >85° {} <10mm {} small-objects {} covered {:.1}% object-features {} veil-points {}",
        v.scans,
        v.lines,
        v.steep,
        v.short,
        v.objects,
        v.covered_pct(),
        objects,
        veils
    );
    Ok(())
}
