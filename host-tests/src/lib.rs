//! Host-side tools for pfe (std allowed here). The folders, by role:
//!
//! | module | what |
//! | --- | --- |
//! | [`cli`] | the `pfe` command line: one clap tree, one file per subcommand |
//! | [`device`] | the LMS200 side: [`device::emulator`] (state machine, range sources, in-process link, pty/TCP transports), [`device::record`] and its [`device::tty`] adapters |
//! | [`scene`] | the scene simulator: shapes, ray casting, range model, scene generators, ground truth with Cramér–Rao bounds, SVG |
//! | [`methods`] | one [`methods::Method`] interface: the [`methods::Pfe`] adapter of pfe-core and the [`methods::baselines`] (split-and-merge, ACF) |
//! | [`eval`] | scoring against ground truth ([`eval::score`]), the paper's comparison with its report and plots, host benchmarks ([`eval::bench`]) |
//! | [`formats`] | recorded scans: CSV, CARMEN, Hokuyo, raw LMS200 captures, ROS 2 bags (MCAP); the JSON output |
//! | [`foxglove`] | scans and features as a Foxglove MCAP file |
//! | [`plot`] | one scan with its marks and features as SVG (Fig. 7 of the paper) |
//! | [`qemu`] | running the firmware under QEMU and reading its frames (demo, bench-mcu, size, end-to-end tests) |
//! | [`soak`] | long runs with damage through emulator, driver, pfe-core and frames (in-process, pty, QEMU) |
//! | [`skip`] | reporting tests that cannot run (listed by `cargo xtask test`, failures in CI) |
//! | [`docs`] | sections of generated Markdown documents (shared with xtask) |

pub mod cli;
pub mod device;
pub mod docs;
pub mod eval;
pub mod formats;
pub mod foxglove;
pub mod link;
pub mod methods;
pub mod outfile;
pub mod plot;
pub mod qemu;
pub mod scene;
pub mod skip;
pub mod soak;
