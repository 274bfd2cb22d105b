//! The LMS200 settings that `emulate` and `record` take.

use lms2xx::codec::types::{Baud, Unit, Variant};

/// `--baud BPS`: one of the LMS200's rates.
pub fn baud(s: &str) -> Result<Baud, String> {
    let b: u32 = s.parse().map_err(|e| format!("--baud: {e}"))?;
    Baud::from_bps(b).ok_or_else(|| format!("unsupported baud {b}"))
}

/// `--variant ANGLE/RES`, e.g. `180/0.5`.
pub fn variant(v: &str) -> Result<Variant, String> {
    let (a, r) = v
        .split_once('/')
        .ok_or("--variant ANGLE/RES, e.g. 180/0.5")?;
    let a: u16 = a.parse().map_err(|e| format!("{e}"))?;
    let r: f32 = r.parse().map_err(|e| format!("{e}"))?;
    let var = Variant::new(a, (r * 100.0).round() as u16);
    if var.is_valid() {
        Ok(var)
    } else {
        Err(format!("invalid variant {v}"))
    }
}

/// `--unit mm|cm`.
pub fn unit(s: &str) -> Result<Unit, String> {
    match s {
        "mm" => Ok(Unit::Mm),
        "cm" => Ok(Unit::Cm),
        other => Err(format!("unknown unit {other}")),
    }
}

/// `--baud`, `--variant`, `--unit` (unset: the device's or driver's default; each command
/// says which in its help).
#[derive(clap::Args, Debug)]
pub struct LmsArgs {
    /// Serial rate: 9600, 19200, 38400 or 500000.
    #[arg(long, value_name = "BPS", value_parser = baud)]
    pub baud: Option<Baud>,
    /// Angle/resolution, e.g. 180/0.5.
    #[arg(long, value_name = "ANGLE/RES", value_parser = variant)]
    pub variant: Option<Variant>,
    /// Range unit: mm or cm.
    #[arg(long, value_name = "mm|cm", value_parser = unit)]
    pub unit: Option<Unit>,
}
