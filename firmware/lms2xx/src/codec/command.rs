//! Host→LMS command encoders, writing complete telegrams into a caller buffer.

use super::frame::{encode_parts, FrameError, HOST_ADDRESS};
use super::reply::ConfigBlock;
use super::types::{Baud, Variant};

/// Installation-mode password of the LMS2xx.
pub const PASSWORD: [u8; 8] = *b"SICK_LMS";

/// Command codes (first payload byte).
pub mod code {
    /// Reset.
    pub const RESET: u8 = 0x10;
    /// Select operating mode (`20 xx`).
    pub const MODE: u8 = 0x20;
    /// Request measured values.
    pub const REQUEST_VALUES: u8 = 0x30;
    /// Request status.
    pub const STATUS: u8 = 0x31;
    /// Request error log.
    pub const ERRORS: u8 = 0x32;
    /// Request type string.
    pub const TYPE: u8 = 0x3A;
    /// Set variant.
    pub const VARIANT: u8 = 0x3B;
    /// Read configuration.
    pub const GET_CONFIG: u8 = 0x74;
    /// Write configuration.
    pub const SET_CONFIG: u8 = 0x77;
}

/// Operating-mode bytes of the `20 xx` command.
pub mod mode {
    /// Installation (setup) mode, followed by the 8-byte password.
    pub const INSTALL: u8 = 0x00;
    /// Continuous output of all values.
    pub const CONTINUOUS: u8 = 0x24;
    /// Measured values on request.
    pub const ON_REQUEST: u8 = 0x25;
}

/// One host→LMS command.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum Command<'a> {
    /// `20 00` + password: installation mode.
    Install(&'a [u8; 8]),
    /// `20 40/41/42/48`: switch baud (reply comes at the old rate).
    SetBaud(Baud),
    /// `20 24`: continuous output of all values.
    Continuous,
    /// `20 25`: values on request (power-on default).
    OnRequest,
    /// `20 xx` with any other mode byte and no data.
    Mode(u8),
    /// `3B aa aa rr rr`: scan variant.
    SetVariant(Variant),
    /// `31`: status.
    Status,
    /// `32`: error log.
    ErrorLog,
    /// `3A`: type string.
    Type,
    /// `74`: read configuration.
    GetConfig,
    /// `77` + 34-byte (or 32-byte) configuration block; needs installation mode.
    SetConfig(&'a ConfigBlock),
    /// `30 mm`: measured values on request (`01` = all values).
    RequestValues(u8),
    /// `10`: reset.
    Reset,
}

impl Command<'_> {
    /// Writes the complete telegram (STX … CRC) into `out`; returns its length.
    ///
    /// ```
    /// use lms2xx::codec::command::Command;
    /// let mut buf = [0u8; 64];
    /// let n = Command::Status.encode(&mut buf)?;
    /// assert_eq!(&buf[..n], &[0x02, 0x00, 0x01, 0x00, 0x31, 0x15, 0x12]);
    /// # Ok::<(), lms2xx::codec::frame::FrameError>(())
    /// ```
    pub fn encode(&self, out: &mut [u8]) -> Result<usize, FrameError> {
        let enc = |parts: &[&[u8]], out: &mut [u8]| encode_parts(HOST_ADDRESS, parts, out);
        match self {
            Command::Install(pw) => enc(&[&[code::MODE, mode::INSTALL], &pw[..]], out),
            Command::SetBaud(b) => enc(&[&[code::MODE, b.mode_code()]], out),
            Command::Continuous => enc(&[&[code::MODE, mode::CONTINUOUS]], out),
            Command::OnRequest => enc(&[&[code::MODE, mode::ON_REQUEST]], out),
            Command::Mode(m) => enc(&[&[code::MODE, *m]], out),
            Command::SetVariant(v) => {
                let [a0, a1] = v.angle_deg.to_le_bytes();
                let [r0, r1] = v.resolution_cdeg.to_le_bytes();
                enc(&[&[code::VARIANT, a0, a1, r0, r1]], out)
            }
            Command::Status => enc(&[&[code::STATUS]], out),
            Command::ErrorLog => enc(&[&[code::ERRORS]], out),
            Command::Type => enc(&[&[code::TYPE]], out),
            Command::GetConfig => enc(&[&[code::GET_CONFIG]], out),
            Command::SetConfig(c) => enc(&[&[code::SET_CONFIG], c.as_bytes()], out),
            Command::RequestValues(m) => enc(&[&[code::REQUEST_VALUES, *m]], out),
            Command::Reset => enc(&[&[code::RESET]], out),
        }
    }

    /// The reply code the device answers with (`command + 0x80`; A0 for all `20 xx`).
    ///
    /// The reset command is answered with 0x91 (then 0x90 after the restart).
    pub fn reply_code(&self) -> u8 {
        match self {
            Command::Reset => 0x91,
            _ => self.code().wrapping_add(0x80),
        }
    }

    /// The command code (first payload byte).
    pub fn code(&self) -> u8 {
        match self {
            Command::Install(_)
            | Command::SetBaud(_)
            | Command::Continuous
            | Command::OnRequest
            | Command::Mode(_) => code::MODE,
            Command::SetVariant(_) => code::VARIANT,
            Command::Status => code::STATUS,
            Command::ErrorLog => code::ERRORS,
            Command::Type => code::TYPE,
            Command::GetConfig => code::GET_CONFIG,
            Command::SetConfig(_) => code::SET_CONFIG,
            Command::RequestValues(_) => code::REQUEST_VALUES,
            Command::Reset => code::RESET,
        }
    }
}
