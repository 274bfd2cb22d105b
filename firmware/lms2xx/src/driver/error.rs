//! The driver's error type.

use crate::codec::frame::FrameError;

/// Errors of the LMS200 [`Driver`](crate::driver::Driver), generic over the bus error `E`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum Error<E> {
    /// The UART (or its baud switch) failed.
    Io(E),
    /// The UART accepted no byte (`write` returned `Ok(0)`).
    WriteZero,
    /// No reply to `command` after every try.
    Timeout {
        /// Command code.
        command: u8,
    },
    /// The device answered `command` with NAK on every try.
    Nak {
        /// Command code.
        command: u8,
    },
    /// No baud rate gave an answer.
    NoDevice,
    /// The device refused `command` (A0 code ≠ 0, BB / F7 not ok, 0x92).
    Rejected {
        /// Command code.
        command: u8,
        /// Answer code (A0 `rr`, BB/F7 ok byte, or 0x92).
        code: u8,
    },
    /// The reply to `command` did not have the expected layout.
    BadReply {
        /// Command code.
        command: u8,
    },
    /// The device reset (0x90 / 0x91) while a command was waiting for its reply.
    DeviceReset,
    /// No scan arrived within the silence timeout, even after re-initialising.
    Silence,
    /// A command could not be encoded (a bug: the buffers are sized for every command).
    Encode(FrameError),
    /// The configuration asks for something the device cannot do (e.g. an invalid variant).
    InvalidConfig,
}

impl<E> From<FrameError> for Error<E> {
    fn from(e: FrameError) -> Self {
        Error::Encode(e)
    }
}

impl<E: core::fmt::Debug> core::fmt::Display for Error<E> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Error::Io(e) => write!(f, "UART error: {e:?}"),
            Error::WriteZero => f.write_str("UART wrote no byte"),
            Error::Timeout { command } => write!(f, "no reply to command {command:#04x}"),
            Error::Nak { command } => write!(f, "command {command:#04x} NAKed on every try"),
            Error::NoDevice => f.write_str("no LMS answered at any baud rate"),
            Error::Rejected { command, code } => {
                write!(f, "command {command:#04x} refused (code {code:#04x})")
            }
            Error::BadReply { command } => write!(f, "malformed reply to {command:#04x}"),
            Error::DeviceReset => f.write_str("device reset during a command"),
            Error::Silence => f.write_str("no scan within the silence timeout"),
            Error::Encode(e) => write!(f, "cannot encode command: {e}"),
            Error::InvalidConfig => f.write_str("invalid driver configuration"),
        }
    }
}

impl<E: core::fmt::Debug> core::error::Error for Error<E> {}
