//! LMS200 serial protocol: telegram codec (sans-IO), commands, replies, driver.
