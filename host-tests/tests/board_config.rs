//! pfe-eval's copy of the board's configuration is the firmware's (pfe-eval does not depend on
//! the firmware crate, so that it publishes without it).

use firmware::app::ConfigChoice;
use pfe_core::Config;
use pfe_eval::scene::adversarial::BOARD_CONFIG;

#[test]
fn pfe_eval_scores_the_board_s_configuration() {
    assert_eq!(BOARD_CONFIG, ConfigChoice::Default.config());
    // and it is not a configuration that would pass whichever it were
    assert_ne!(BOARD_CONFIG, ConfigChoice::Paper.config());
    assert_ne!(BOARD_CONFIG, Config::default());
    // Everything on, as `pfe extract --format lms200` runs it.
    const { assert!(BOARD_CONFIG.scrutiny) };
    assert_eq!(
        BOARD_CONFIG,
        Config::default()
            .with_sigma_r(pfe_formats::Format::Lms200.sigma_r())
            .with_sigma_sys(pfe_formats::Format::Lms200.sigma_sys())
    );
}
