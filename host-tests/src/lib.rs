//! Host-side tools for pfe: scene simulator with ground truth, scorer, baselines, LMS200
//! device emulator, file formats, plots, evaluation and benchmarks (std allowed here).

pub mod baselines;
pub mod bench;
pub mod docs;
pub mod emulator;
pub mod eval;
pub mod formats;
pub mod foxglove;
pub mod method;
pub mod plot;
pub mod record;
pub mod score;
pub mod sim;
