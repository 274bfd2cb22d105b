//! Quick score of PFE (paper and default configurations) on simulated scans.
//!
//! `cargo run -p host-tests --release --example score -- --kind mixed --scans 100 --sigma 5 [--seed 1]`

use anyhow::{bail, Context, Result};
use pfe_eval::methods::{Method, Pfe};
use pfe_eval::quick_report;
use pfe_eval::scene::SceneKind;

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (mut kind, mut scans, mut sigma, mut seed) = (SceneKind::Mixed, 100usize, 5.0f32, 1u64);
    let mut it = args.iter();
    while let Some(a) = it.next() {
        let mut val = || it.next().with_context(|| format!("{a} needs a value"));
        match a.as_str() {
            "--kind" => kind = val()?.parse().map_err(anyhow::Error::msg)?,
            "--scans" => scans = val()?.parse()?,
            "--sigma" => sigma = val()?.parse()?,
            "--seed" => seed = val()?.parse()?,
            "-h" | "--help" => {
                println!("score [--kind office|clutter|pillars|corridor|mixed] [--scans N] [--sigma MM] [--seed S]");
                return Ok(());
            }
            other => bail!("unknown argument `{other}`"),
        }
    }
    let mut paper = Pfe::paper();
    let mut default = Pfe::default_config();
    let mut methods: [&mut dyn Method; 2] = [&mut paper, &mut default];
    print!("{}", quick_report(&mut methods, kind, scans, sigma, seed));
    Ok(())
}
