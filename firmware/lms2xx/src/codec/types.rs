//! Small value types shared by commands, replies, the driver and the emulator.

/// Serial line speeds the LMS200 supports.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Baud {
    /// 9600 bps (power-on default).
    B9600,
    /// 19200 bps.
    B19200,
    /// 38400 bps.
    B38400,
    /// 500000 bps (RS-422 only on real hardware).
    B500000,
}

impl Baud {
    /// All rates, in the order a baud probe tries them.
    pub const ALL: [Baud; 4] = [Baud::B9600, Baud::B19200, Baud::B38400, Baud::B500000];

    /// Bits per second.
    pub const fn bps(self) -> u32 {
        match self {
            Baud::B9600 => 9600,
            Baud::B19200 => 19200,
            Baud::B38400 => 38400,
            Baud::B500000 => 500_000,
        }
    }

    /// The rate for `bps`, if the LMS supports it.
    pub const fn from_bps(bps: u32) -> Option<Baud> {
        match bps {
            9600 => Some(Baud::B9600),
            19200 => Some(Baud::B19200),
            38400 => Some(Baud::B38400),
            500_000 => Some(Baud::B500000),
            _ => None,
        }
    }

    /// Mode byte of the `20 xx` command that selects this rate.
    pub const fn mode_code(self) -> u8 {
        match self {
            Baud::B9600 => 0x42,
            Baud::B19200 => 0x41,
            Baud::B38400 => 0x40,
            Baud::B500000 => 0x48,
        }
    }

    /// The rate selected by mode byte `code` of a `20 xx` command.
    pub const fn from_mode_code(code: u8) -> Option<Baud> {
        match code {
            0x42 => Some(Baud::B9600),
            0x41 => Some(Baud::B19200),
            0x40 => Some(Baud::B38400),
            0x48 => Some(Baud::B500000),
            _ => None,
        }
    }

    /// Baud word at B1 offsets 116–117.
    pub const fn status_word(self) -> u16 {
        match self {
            Baud::B9600 => 0x8067,
            Baud::B19200 => 0x8033,
            Baud::B38400 => 0x8019,
            Baud::B500000 => 0x8001,
        }
    }

    /// The rate for a B1 baud word.
    pub const fn from_status_word(w: u16) -> Option<Baud> {
        match w {
            0x8067 => Some(Baud::B9600),
            0x8033 => Some(Baud::B19200),
            0x8019 => Some(Baud::B38400),
            0x8001 => Some(Baud::B500000),
            _ => None,
        }
    }
}

/// Scan variant: field of view and angular resolution (command 0x3B).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Variant {
    /// Field of view, degrees (100 or 180).
    pub angle_deg: u16,
    /// Resolution, 1/100 degree (25, 50 or 100).
    pub resolution_cdeg: u16,
}

impl Variant {
    /// 180° at 1°: 181 values.
    pub const A180_R100: Variant = Variant::new(180, 100);
    /// 180° at 0.5°: 361 values (power-on default).
    pub const A180_R050: Variant = Variant::new(180, 50);
    /// 100° at 1°: 101 values.
    pub const A100_R100: Variant = Variant::new(100, 100);
    /// 100° at 0.5°: 201 values.
    pub const A100_R050: Variant = Variant::new(100, 50);
    /// 100° at 0.25°: 401 values.
    pub const A100_R025: Variant = Variant::new(100, 25);
    /// The five combinations an LMS200 accepts.
    pub const VALID: [Variant; 5] = [
        Variant::A180_R100,
        Variant::A180_R050,
        Variant::A100_R100,
        Variant::A100_R050,
        Variant::A100_R025,
    ];

    /// Most values in one scan of any [`Variant::VALID`] variant (100° at 0.25°: 401).
    // Evaluated at compile time: an index out of range would be a build error, not a panic.
    #[allow(clippy::indexing_slicing)]
    pub const MAX_VALUES: usize = {
        let mut max = 0;
        let mut i = 0;
        while i < Variant::VALID.len() {
            let n = Variant::VALID[i].values();
            if n > max {
                max = n;
            }
            i += 1;
        }
        max
    };

    /// A variant (not checked; see [`Variant::is_valid`]).
    pub const fn new(angle_deg: u16, resolution_cdeg: u16) -> Self {
        Self {
            angle_deg,
            resolution_cdeg,
        }
    }

    /// The variant whose scans have `n` values (the five counts differ).
    pub fn from_values(n: usize) -> Option<Variant> {
        Self::VALID.into_iter().find(|v| v.values() == n)
    }

    /// True for one of the five combinations the device accepts.
    pub fn is_valid(&self) -> bool {
        Self::VALID.contains(self)
    }

    /// Number of values per scan (`angle / resolution + 1`), 0 for a zero resolution.
    pub const fn values(&self) -> usize {
        if self.resolution_cdeg == 0 {
            return 0;
        }
        (self.angle_deg as usize * 100) / self.resolution_cdeg as usize + 1
    }

    /// Resolution in degrees.
    pub fn resolution_deg(&self) -> f32 {
        f32::from(self.resolution_cdeg) / 100.0
    }

    /// Bearing of value 0 in degrees, with the field centred on 0 (−90° for 180°).
    pub fn start_deg(&self) -> f32 {
        -f32::from(self.angle_deg) / 2.0
    }

    /// Largest scan rate the mirror allows, Hz (75 / 37.5 / 18.75 for 1° / 0.5° / 0.25°).
    pub fn max_rate_hz(&self) -> f32 {
        match self.resolution_cdeg {
            25 => 18.75,
            50 => 37.5,
            _ => 75.0,
        }
    }
}

impl Default for Variant {
    fn default() -> Self {
        Variant::A180_R050
    }
}

/// Distance unit of the range values.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Unit {
    /// Centimetres (power-on default).
    Cm,
    /// Millimetres.
    Mm,
    /// Decimetres (count-word code 10, CARMEN only).
    Dm,
}

impl Unit {
    /// Millimetres per range unit.
    pub const fn mm_per_unit(self) -> f32 {
        match self {
            Unit::Cm => 10.0,
            Unit::Mm => 1.0,
            Unit::Dm => 100.0,
        }
    }

    /// Unit from the two count-word bits 14–15 (00 cm, 01 mm, 10 dm); 11 is undefined.
    pub const fn from_count_bits(bits: u16) -> Option<Unit> {
        match bits & 0b11 {
            0 => Some(Unit::Cm),
            1 => Some(Unit::Mm),
            2 => Some(Unit::Dm),
            _ => None,
        }
    }

    /// Count-word bits 14–15 for this unit.
    pub const fn count_bits(self) -> u16 {
        match self {
            Unit::Cm => 0,
            Unit::Mm => 1,
            Unit::Dm => 2,
        }
    }

    /// Unit from config byte 6 / B1 byte 122 (0 cm, 1 mm, 2 dm).
    pub const fn from_config(b: u8) -> Option<Unit> {
        match b {
            0 => Some(Unit::Cm),
            1 => Some(Unit::Mm),
            2 => Some(Unit::Dm),
            _ => None,
        }
    }

    /// Config byte 6 value for this unit.
    pub const fn config_byte(self) -> u8 {
        match self {
            Unit::Cm => 0,
            Unit::Mm => 1,
            Unit::Dm => 2,
        }
    }
}

/// Measuring mode (config byte 5): how each B0 value word splits into range and flag bits.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct MeasuringMode(pub u8);

impl MeasuringMode {
    /// 0x00: 8 m / 80 m, fields A, B and dazzle (power-on default).
    pub const M8_FIELDS_AB_DAZZLE: MeasuringMode = MeasuringMode(0x00);
    /// 0x06: 32 m, field A (MRPT uses it for mm).
    pub const M32_FIELD_A: MeasuringMode = MeasuringMode(0x06);
    /// 0x0F: 32 m, immediate, no flags.
    pub const M32_IMMEDIATE: MeasuringMode = MeasuringMode(0x0F);

    /// Number of low bits holding the range (13, 14, 15 or 16). Unknown modes use 13.
    pub const fn range_bits(self) -> u32 {
        match self.0 {
            0x03 | 0x04 => 14,
            0x05 | 0x06 => 15,
            0x0F | 0x3F => 16,
            _ => 13,
        }
    }

    /// Mask of the range bits.
    pub const fn range_mask(self) -> u16 {
        match self.range_bits() {
            16 => 0xFFFF,
            b => (1u16 << b) - 1,
        }
    }

    /// Largest valid range code; codes above are reserved error codes (none in the 16-bit modes).
    pub const fn max_valid(self) -> u16 {
        match self.range_bits() {
            16 => 0xFFFF,
            _ => self.range_mask() - 9,
        }
    }
}

impl Default for MeasuringMode {
    fn default() -> Self {
        MeasuringMode::M8_FIELDS_AB_DAZZLE
    }
}
