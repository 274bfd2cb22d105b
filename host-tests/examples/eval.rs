//! The evaluation (`cargo xtask eval` runs this in release):
//! `cargo run -p host-tests --release --example eval -- [--scans 100] [--seed 1] [--out docs]`.

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    pfe_cli::eval::cli(&args)
}
