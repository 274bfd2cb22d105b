//! The scan telegrams (B0) the emulated device sends: range codes, injected damage, pacing.

use lms2xx::codec::reply::code as rcode;
use lms2xx::codec::types::{MeasuringMode, Unit};
use rand::Rng;

use super::{telegram, Emulator, SentScan};

impl Emulator {
    /// Encodes range `mm` as a code for the current unit and mode.
    pub fn encode_range(mm: f32, unit: Unit, mode: MeasuringMode) -> u16 {
        let mask = mode.range_mask();
        if !mm.is_finite() || mm <= 0.0 {
            return mask;
        }
        let v = (mm / unit.mm_per_unit()).round();
        if v > f32::from(mode.max_valid()) {
            if mode.range_bits() >= 16 {
                mode.max_valid()
            } else {
                mask - 8
            }
        } else {
            v as u16
        }
    }

    pub(super) fn make_b0(&mut self) -> (Vec<u8>, u32) {
        let n = self.variant.values();
        let step = self.variant.resolution_deg();
        let ranges = self.source.next_scan(n, self.variant.start_deg(), step);
        let unit = self.block.unit().unwrap_or(Unit::Cm);
        let mode = self.block.measuring_mode();
        let words: Vec<u16> = (0..n)
            .map(|i| Self::encode_range(ranges.get(i).copied().unwrap_or(f32::NAN), unit, mode))
            .collect();
        let seq = self.report.scans.len() as u32;
        let count = (n as u16 & 0x3FF) | (unit.count_bits() << 14);
        let mut p = vec![rcode::VALUES];
        p.extend(count.to_le_bytes());
        for w in &words {
            p.extend(w.to_le_bytes());
        }
        if self.block.realtime_index() {
            p.push(seq as u8);
        }
        p.push(self.cfg.status);
        let t = telegram::device_telegram(&p).unwrap_or_default();
        self.report.scans.push(SentScan {
            seq,
            words,
            ranges_mm: ranges,
            unit,
            mode,
            damaged: false,
        });
        (t, seq)
    }

    /// Applies at most one damaging fault to telegram `t`; true when it was damaged.
    pub(super) fn damage(&mut self, t: &mut Vec<u8>) -> bool {
        let f = &self.cfg.faults;
        let (pf, pd, pu, pt) = (f.bit_flip, f.drop_byte, f.duplicate_byte, f.truncate);
        let r: f64 = self.rng.gen();
        let len = t.len();
        if len < 2 {
            return false;
        }
        if r < pf {
            let i = self.rng.gen_range(0..len);
            t[i] ^= 1 << self.rng.gen_range(0..8);
        } else if r < pf + pd {
            t.remove(self.rng.gen_range(0..len));
        } else if r < pf + pd + pu {
            let i = self.rng.gen_range(0..len);
            let b = t[i];
            t.insert(i, b);
        } else if r < pf + pd + pu + pt {
            t.truncate(self.rng.gen_range(1..len));
        } else {
            return false;
        }
        true
    }

    pub(super) fn send_b0(&mut self, at: u64, (mut t, seq): (Vec<u8>, u32)) {
        if self.damage(&mut t) {
            if let Some(s) = self.report.scans.get_mut(seq as usize) {
                s.damaged = true;
            }
        }
        if self.rng.gen_bool(self.cfg.faults.garbage.clamp(0.0, 1.0)) {
            let n = self.rng.gen_range(1..=40);
            let g: Vec<u8> = (0..n).map(|_| self.rng.gen()).collect();
            self.emit(at, &g, None);
        }
        self.emit(at, &t, Some(seq));
    }
}
