//! `pfe`: run the prediction-based feature extractor on recorded scans (see
//! [`host_tests::cli`]).
#![forbid(unsafe_code)]

fn main() -> std::process::ExitCode {
    host_tests::cli::main()
}
