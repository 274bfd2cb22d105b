//! The one bridge from LMS scans to pfe-core: [`RawScan`] (raw range codes with their
//! geometry and unit) from the driver's [`ScanData`], and from it the pfe-core [`Scan`].

use pfe_core::{Ranges, Scan, ScanGeometry};

use lms2xx::codec::types::MeasuringMode;
use lms2xx::driver::ScanData;

/// One scan as the driver delivers it: raw range codes (measuring-mode flag bits removed).
#[derive(Clone, Copy, Debug)]
pub struct RawScan<'a> {
    /// Beam geometry of the scanner's variant.
    pub geometry: ScanGeometry,
    /// Range codes; 0 and codes above 8182 are no return.
    pub values: &'a [u16],
    /// mm per code: 1.0 in mm mode, 10.0 in cm mode.
    pub mm_per_unit: f32,
    /// Largest valid code (8182 in the 8 m / 80 m measuring modes).
    pub max_valid: u16,
    /// Firmware time when the telegram was complete, ms (the driver's clock; 0 if unknown).
    pub time_ms: u32,
}

impl<'a> RawScan<'a> {
    /// A scan in the 8 m / 80 m measuring modes (largest valid code 8182).
    pub fn lms_8m(geometry: ScanGeometry, values: &'a [u16], mm_per_unit: f32) -> Self {
        Self {
            geometry,
            values,
            mm_per_unit,
            max_valid: MeasuringMode::M8_FIELDS_AB_DAZZLE.max_valid(),
            time_ms: 0,
        }
    }

    /// The pfe-core input for this scan, as `pfe extract --format lms200` builds it
    /// ([`Scan::lms2xx`]): the raw codes, the interleaved sweeps of the geometry's step (2 at
    /// 0.5°, 4 at 0.25°) and the grid the readings lie on.
    ///
    /// ```
    /// use firmware::app::RawScan;
    /// use pfe_core::ScanGeometry;
    /// let codes: Vec<u16> = (0..361).map(|i| 1000 + i).collect();
    /// let scan = RawScan::lms_8m(ScanGeometry::LMS200_180_050, &codes, 1.0).to_pfe();
    /// assert_eq!((scan.sweeps, scan.quantum), (2, 1.0));
    /// ```
    pub fn to_pfe(&self) -> Scan<'a> {
        let ranges = Ranges::Raw {
            values: self.values,
            mm_per_unit: self.mm_per_unit,
            max_valid: self.max_valid,
        };
        Scan::lms2xx(self.geometry, ranges)
    }
}

/// The driver's [`ScanData`] as pfe-core input: the geometry of the scan's variant, the scan as
/// a [`RawScan`] and as a [`Scan`] (raw codes, no copy). A trait because `ScanData` lives in
/// `lms2xx`, which knows nothing of pfe-core.
///
/// ```
/// use firmware::app::ScanDataExt;
/// use lms2xx::driver::ScanData;
/// let scan = ScanData::default();
/// assert_eq!(scan.raw().values.len(), scan.len());
/// ```
pub trait ScanDataExt {
    /// Beam geometry (centred field, value 0 on the right, counter-clockwise).
    fn geometry(&self) -> ScanGeometry;
    /// The scan as [`RawScan`] (raw codes, no copy).
    fn raw(&self) -> RawScan<'_>;
    /// The scan as pfe-core input (raw codes, no copy).
    fn as_pfe_scan(&self) -> Scan<'_>;
}

impl ScanDataExt for ScanData {
    fn geometry(&self) -> ScanGeometry {
        let mut g = ScanGeometry::lms200(
            f32::from(self.variant.angle_deg),
            self.variant.resolution_deg(),
        );
        g.r_max = f32::from(self.max_valid()) * self.mm_per_unit();
        g
    }

    fn raw(&self) -> RawScan<'_> {
        RawScan {
            geometry: self.geometry(),
            values: self.codes(),
            mm_per_unit: self.mm_per_unit(),
            max_valid: self.max_valid(),
            time_ms: self.time_ms,
        }
    }

    fn as_pfe_scan(&self) -> Scan<'_> {
        self.raw().to_pfe()
    }
}
