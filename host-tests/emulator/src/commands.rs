//! The commands the emulated device answers.

use lms2xx::codec::command::{code as ccode, mode as cmode, PASSWORD};
use lms2xx::codec::frame::{ACK, NAK};
use lms2xx::codec::reply::{code as rcode, status_offset, ConfigBlock};
use lms2xx::codec::types::{Baud, Unit, Variant};

use super::Emulator;

impl Emulator {
    pub(super) fn command(&mut self, now: u64, p: &[u8]) {
        let Some((&cmd, data)) = p.split_first() else {
            return;
        };
        self.report.commands.push(cmd);
        let ack_at = now + self.cfg.ack_delay_us;
        if self.nak_left > 0 {
            self.nak_left -= 1;
            self.emit(ack_at, &[NAK], None);
            return;
        }
        let t = self.emit(ack_at, &[ACK], None);
        let at = t + self.cfg.reply_delay_us;
        if self.cfg.unsupported.contains(&cmd) {
            self.reply(at, &[rcode::INCORRECT]);
            return;
        }
        match (cmd, data) {
            (ccode::MODE, [m, pw @ ..]) => {
                let m = *m;
                if m == cmode::INSTALL {
                    let ok = pw == PASSWORD.as_slice();
                    self.install = ok;
                    self.reply(at, &[rcode::MODE, if ok { 0 } else { 1 }]);
                    return;
                }
                self.install = false;
                if Baud::from_mode_code(m).is_some_and(|b| self.cfg.refused_bauds.contains(&b)) {
                    self.reply(at, &[rcode::MODE, 1]);
                    return;
                }
                let end = self.reply(at, &[rcode::MODE, 0]);
                if let Some(b) = Baud::from_mode_code(m) {
                    self.pending_baud = Some((end, b));
                } else if m == cmode::CONTINUOUS {
                    if !self.streaming {
                        self.streaming = true;
                        self.next_scan_us = end + 5000;
                    }
                } else if m == cmode::ON_REQUEST {
                    self.streaming = false;
                }
            }
            (ccode::REQUEST_VALUES, _) => {
                let t = self.make_b0();
                self.send_b0(at, t);
            }
            (ccode::STATUS, []) => {
                let b1 = self.b1();
                self.reply(at, &b1);
            }
            (ccode::ERRORS, []) => {
                self.reply(at, &[rcode::ERRORS]);
            }
            (ccode::TYPE, []) => {
                let mut p = vec![rcode::TYPE];
                p.extend(self.cfg.type_string.as_bytes());
                self.reply(at, &p);
            }
            (ccode::VARIANT, [a0, a1, r0, r1]) => {
                let v = Variant::new(
                    u16::from_le_bytes([*a0, *a1]),
                    u16::from_le_bytes([*r0, *r1]),
                );
                let ok = v.is_valid();
                if ok {
                    self.variant = v;
                }
                self.reply(at, &[rcode::VARIANT, u8::from(ok), *a0, *a1, *r0, *r1]);
            }
            (ccode::GET_CONFIG, []) => {
                let mut p = vec![rcode::CONFIG];
                p.extend(self.block.as_bytes());
                self.reply(at, &p);
            }
            (ccode::SET_CONFIG, block) => {
                let parsed = ConfigBlock::from_bytes(block);
                let ok = self.install && parsed.is_some();
                if let (true, Some(b)) = (ok, parsed) {
                    self.block = b;
                }
                let mut p = vec![rcode::CONFIG_SET, u8::from(ok)];
                p.extend(parsed.unwrap_or(self.block).as_bytes());
                self.reply(at, &p);
            }
            (ccode::RESET, []) => {
                self.reply(at, &[rcode::RESET_ACK]);
                self.reset(self.line_free_us);
            }
            _ => {
                self.reply(at, &[rcode::INCORRECT]);
            }
        }
    }

    /// Device reset at `t`: deaf for the reset time, then 9600 baud, request mode, 0x90.
    pub(super) fn reset(&mut self, t: u64) {
        self.report.resets += 1;
        self.streaming = false;
        self.install = false;
        self.pending_baud = None;
        self.decoder.clear();
        self.reboot_at_us = Some(t + self.cfg.reset_time_us);
    }

    /// The operating mode B1 reports (payload index 8): `00` in installation mode, `24` while
    /// streaming, `25` (values on request, the power-on mode) otherwise.
    pub fn operating_mode(&self) -> u8 {
        if self.install {
            cmode::INSTALL
        } else if self.streaming {
            cmode::CONTINUOUS
        } else {
            cmode::ON_REQUEST
        }
    }

    /// The B1 payload (code + 152 data bytes) at S1's offsets (protocol notes §6).
    pub(super) fn b1(&self) -> Vec<u8> {
        let mut p = vec![0u8; status_offset::PAYLOAD_LEN - 1];
        p[0] = rcode::STATUS;
        p[1..8].copy_from_slice(b"V02.10 ");
        p[status_offset::OPERATING_MODE] = self.operating_mode();
        p[status_offset::DEVICE_STATUS] = 0;
        p[10..18].copy_from_slice(b"07380000");
        // 18: variant type (0 = standard type 6); 124–130: PROM software version.
        p[18] = 0;
        p[124..131].copy_from_slice(b"V02.10 ");
        p[status_offset::MEASURING_MODE] = self.block.measuring_mode().0;
        p[status_offset::SCAN_ANGLE..status_offset::SCAN_ANGLE + 2]
            .copy_from_slice(&self.variant.angle_deg.to_le_bytes());
        p[status_offset::RESOLUTION..status_offset::RESOLUTION + 2]
            .copy_from_slice(&self.variant.resolution_cdeg.to_le_bytes());
        p[status_offset::BAUD..status_offset::BAUD + 2]
            .copy_from_slice(&self.baud.status_word().to_le_bytes());
        p[status_offset::ADDRESS] = 0;
        p[status_offset::UNIT] = self.block.unit().map_or(0, Unit::config_byte);
        p
    }
}
