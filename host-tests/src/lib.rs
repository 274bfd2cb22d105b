//! Host-side tools for pfe: scene simulator with ground truth, scorer, baselines, LMS200
//! device emulator, file formats, plots, evaluation and benchmarks (std allowed here).

pub mod cli;
pub mod device;
pub mod docs;
pub mod eval;
pub mod formats;
pub mod methods;
pub mod plot;
pub mod qemu;
pub mod scene;
pub mod soak;
