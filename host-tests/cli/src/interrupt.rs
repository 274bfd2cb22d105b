//! Ctrl-C and SIGTERM: the first sets a flag that the long-running subcommands (`emulate`,
//! `record`) poll to stop and clean up; a second one exits at once with code 130.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Once, OnceLock};

static FLAG: OnceLock<Arc<AtomicBool>> = OnceLock::new();
static INSTALL: Once = Once::new();

/// The flag set by SIGINT/SIGTERM once [`install`] ran (never set before).
pub fn flag() -> Arc<AtomicBool> {
    FLAG.get_or_init(|| Arc::new(AtomicBool::new(false)))
        .clone()
}

/// True once SIGINT or SIGTERM arrived.
pub fn requested() -> bool {
    flag().load(Ordering::Relaxed)
}

/// Installs the handler (once per process; later calls do nothing).
pub fn install() {
    INSTALL.call_once(|| {
        let f = flag();
        let r = ctrlc::set_handler(move || {
            if f.swap(true, Ordering::Relaxed) {
                std::process::exit(130);
            }
        });
        if let Err(e) = r {
            eprintln!("pfe: warning: cannot handle Ctrl-C: {e}");
        }
    });
}
