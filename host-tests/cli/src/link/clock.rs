//! Firmware time to wall-clock time: a frame's `time_ms` (ms since the firmware started,
//! wrapping at 2³²) as ns since the Unix epoch.
//!
//! The first frame anchors the firmware clock to its receive time; later frames are the anchor
//! plus the firmware time elapsed since, unwrapped, so their spacing is the firmware's own
//! (free of USB and scheduling jitter). The link keeps frames in order, so a step back is a
//! restart of the firmware: the clock re-anchors to that frame's receive time.
//!
//! ```
//! use pfe_cli::link::clock::FirmwareClock;
//! let mut c = FirmwareClock::new();
//! assert_eq!(c.stamp_ns(u32::MAX, 5_000_000_000), 5_000_000_000);
//! assert_eq!(c.stamp_ns(99, 9_000_000_000), 5_100_000_000); // wrapped: 100 ms later
//! ```

/// Maps firmware `time_ms` to Unix ns (see the module's documentation).
#[derive(Clone, Copy, Debug, Default)]
pub struct FirmwareClock {
    /// (firmware ms, unwrapped ms, Unix ns of unwrapped ms 0) of the last frame.
    last: Option<(u32, u64, i128)>,
}

impl FirmwareClock {
    /// A clock with no anchor yet.
    pub fn new() -> Self {
        Self::default()
    }

    /// The stamp of a frame with firmware time `time_ms`, received at `received_ns`.
    pub fn stamp_ns(&mut self, time_ms: u32, received_ns: u64) -> u64 {
        let ms_ns = |ms: u64| i128::from(ms) * 1_000_000;
        let (unwrapped, anchor) = match self.last {
            Some((prev, prev_unwrapped, anchor)) => {
                let forward = time_ms.wrapping_sub(prev);
                if forward <= u32::MAX / 2 {
                    // Forward (or equal), across a wrap or not.
                    (prev_unwrapped + u64::from(forward), anchor)
                } else {
                    (
                        u64::from(time_ms),
                        i128::from(received_ns) - ms_ns(u64::from(time_ms)),
                    )
                }
            }
            None => (
                u64::from(time_ms),
                i128::from(received_ns) - ms_ns(u64::from(time_ms)),
            ),
        };
        self.last = Some((time_ms, unwrapped, anchor));
        u64::try_from((anchor + ms_ns(unwrapped)).max(0)).unwrap_or(u64::MAX)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spacing_is_the_firmware_s_and_a_restart_reanchors() {
        let mut c = FirmwareClock::new();
        assert_eq!(c.stamp_ns(1_000, 10_000_000_000), 10_000_000_000);
        // Received late: the stamp keeps the firmware's 133 ms.
        assert_eq!(c.stamp_ns(1_133, 10_500_000_000), 10_133_000_000);
        // Restarted firmware (time back): anchored at its receive time.
        assert_eq!(c.stamp_ns(50, 20_000_000_000), 20_000_000_000);
        assert_eq!(c.stamp_ns(150, 20_000_000_001), 20_100_000_000);
    }
}
