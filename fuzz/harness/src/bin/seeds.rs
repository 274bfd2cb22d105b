//! `seeds <out-dir> <shared-dir>`: writes the seed corpora of every fuzz target
//! (`<out-dir>/<target>/`), from `<shared-dir>/docs` (protocol vectors) and `<shared-dir>/data`.
use std::path::PathBuf;

fn main() -> std::process::ExitCode {
    let args: Vec<PathBuf> = std::env::args_os().skip(1).map(PathBuf::from).collect();
    let [out, shared] = args.as_slice() else {
        eprintln!("usage: seeds <out-dir> <shared-dir>");
        return std::process::ExitCode::FAILURE;
    };
    match pfe_fuzz_harness::seeds::generate(out, shared) {
        Ok(n) => {
            println!("seeds: {n} files in {}", out.display());
            std::process::ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("seeds: {e}");
            std::process::ExitCode::FAILURE
        }
    }
}
