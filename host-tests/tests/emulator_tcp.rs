//! The emulator on a TCP socket (as QEMU's `-serial tcp:127.0.0.1:PORT` reaches it), driven by
//! the firmware driver through a small std TCP adapter.

use std::io::{ErrorKind, Read, Write};
use std::net::{TcpListener, TcpStream};
use std::time::Duration;

use lms200_emulator::{serve_tcp, EmulatorConfig, RunLimits, SourceKind, TaggedSource};
use lms2xx::driver::{Config, Driver, SetBaud};
use pfe_cli::device::tty::{StdClock, StdDelay};

struct TcpPort {
    s: TcpStream,
    buf: Vec<u8>,
}

impl TcpPort {
    fn fill(&mut self) -> std::io::Result<()> {
        let mut tmp = [0u8; 2048];
        match self.s.read(&mut tmp) {
            Ok(n) => {
                self.buf.extend_from_slice(&tmp[..n]);
                Ok(())
            }
            Err(e) if e.kind() == ErrorKind::WouldBlock => Ok(()),
            Err(e) => Err(e),
        }
    }
}

impl embedded_io::ErrorType for TcpPort {
    type Error = std::io::Error;
}
impl embedded_io::ReadReady for TcpPort {
    fn read_ready(&mut self) -> std::io::Result<bool> {
        if self.buf.is_empty() {
            self.fill()?;
        }
        Ok(!self.buf.is_empty())
    }
}
impl embedded_io::Read for TcpPort {
    fn read(&mut self, out: &mut [u8]) -> std::io::Result<usize> {
        let n = out.len().min(self.buf.len());
        out[..n].copy_from_slice(&self.buf[..n]);
        self.buf.drain(..n);
        Ok(n)
    }
}
impl embedded_io::Write for TcpPort {
    fn write(&mut self, b: &[u8]) -> std::io::Result<usize> {
        self.s.write_all(b)?;
        Ok(b.len())
    }
    fn flush(&mut self) -> std::io::Result<()> {
        self.s.flush()
    }
}
impl SetBaud for TcpPort {
    fn set_baud(&mut self, _: u32) -> std::io::Result<()> {
        Ok(()) // no baud over TCP
    }
}

#[test]
fn driver_over_tcp_gets_sent_scans() {
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let addr = listener.local_addr().unwrap();
    let cfg = EmulatorConfig {
        source: SourceKind::Tagged,
        ..Default::default()
    };
    let limits = RunLimits {
        max_time: Some(Duration::from_secs(30)),
        ..Default::default()
    };
    let emu = std::thread::spawn(move || serve_tcp(listener, cfg, limits));
    let s = TcpStream::connect(addr).unwrap();
    s.set_nonblocking(true).unwrap();
    let port = TcpPort { s, buf: Vec::new() };
    let mut lms = Driver::new(port, StdDelay, StdClock::default(), Config::default());
    let mut tags = Vec::new();
    for _ in 0..5 {
        let scan = lms.next_scan().unwrap();
        assert_eq!(scan.len(), 361);
        tags.push(TaggedSource::tag_of(scan.codes()).unwrap());
        assert_eq!(
            scan.codes(),
            &TaggedSource::ranges(tags[tags.len() - 1], 361)
                .iter()
                .map(|&r| r as u16)
                .collect::<Vec<_>>()[..]
        );
    }
    assert!(tags.windows(2).all(|w| w[0] < w[1]), "{tags:?}");
    // No baud over TCP: the first probe (at the target rate) is answered.
    assert_eq!(lms.counters().timeouts, 0);
    let (port, _, _) = lms.release();
    drop(port); // closing the connection ends the emulator
    let report = emu.join().unwrap().unwrap();
    assert!(report.scans.len() >= 5);
    assert_eq!(report.garbled_in + report.garbled_out, 0);
}
