//! What the driver needs from the platform beyond `embedded-io` and `embedded-hal`.

use embedded_io::ErrorType;

/// A millisecond time source (wrapping `u32`).
pub trait Clock {
    /// Milliseconds since an arbitrary origin; may wrap.
    fn now_ms(&mut self) -> u32;
}

/// Changing the UART's baud rate (embedded-io has no notion of it).
pub trait SetBaud: ErrorType {
    /// Switches the local UART to `baud` bits per second.
    fn set_baud(&mut self, baud: u32) -> Result<(), Self::Error>;
}
