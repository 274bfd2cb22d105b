//! `pfe`: run the prediction-based feature extractor on recorded scans (see
//! [`pfe_cli`]).
#![forbid(unsafe_code)]

fn main() -> std::process::ExitCode {
    pfe_cli::main()
}
