//! The scanner UART's receive ring: an interrupt handler (the producer) puts each received
//! byte into a lock-free single-producer single-consumer queue ([`heapless::spsc::Queue`],
//! [`RING_SLOTS`] slots: 2047 bytes, 2.8 telegrams of 732 bytes, 41 ms at 500 kBd) and the
//! driver's UART (the consumer) takes them out, so the extractor may run while a telegram
//! arrives.
//!
//! What is lost is counted in [`RxCounters`] (atomics, shared by both ends): bytes dropped
//! because the ring was full (the main loop fell behind), receive overruns (the handler came
//! too late) and line errors; beside them the most bytes ever waiting (the backlog's
//! high-water mark). [`RxConsumer::read`] reports new counts once the bytes before
//! them are read, so the driver returns the loss as a UART error, its decoder resyncs on the next header, and
//! nothing re-initialises the device for it.

use core::sync::atomic::{AtomicU32, Ordering};

use heapless::spsc::{Consumer, Producer, Queue};

/// Ring slots; one stays free, so the ring holds 2047 bytes.
pub const RING_SLOTS: usize = 2048;

/// The receive ring (put it in a `static` and split it once).
pub type RxQueue = Queue<u8, RING_SLOTS>;

/// Losses on the receive path, counted by the producer.
#[derive(Debug, Default)]
pub struct RxCounters {
    ring_full: AtomicU32,
    overruns: AtomicU32,
    line_errors: AtomicU32,
    peak: AtomicU32,
}

impl RxCounters {
    /// All zero (for a `static`).
    pub const fn new() -> Self {
        Self {
            ring_full: AtomicU32::new(0),
            overruns: AtomicU32::new(0),
            line_errors: AtomicU32::new(0),
            peak: AtomicU32::new(0),
        }
    }

    /// Bytes dropped because the ring was full.
    pub fn ring_full(&self) -> u32 {
        self.ring_full.load(Ordering::Relaxed)
    }

    /// Receive overruns of the UART itself.
    pub fn overruns(&self) -> u32 {
        self.overruns.load(Ordering::Relaxed)
    }

    /// Bytes with a framing, noise or parity error (dropped).
    pub fn line_errors(&self) -> u32 {
        self.line_errors.load(Ordering::Relaxed)
    }

    /// The most bytes ever waiting in the ring (the backlog's high-water mark; a full ring
    /// shows as its capacity, `RING_SLOTS - 1`).
    pub fn peak(&self) -> u32 {
        self.peak.load(Ordering::Relaxed)
    }
}

fn count(counter: &AtomicU32) {
    counter.fetch_add(1, Ordering::Relaxed);
}

/// The interrupt handler's end.
pub struct RxProducer<'a, const S: usize = RING_SLOTS> {
    ring: Producer<'a, u8, S>,
    counters: &'a RxCounters,
}

impl<'a, const S: usize> RxProducer<'a, S> {
    /// The producer end `ring`, counting into `counters`.
    pub fn new(ring: Producer<'a, u8, S>, counters: &'a RxCounters) -> Self {
        Self { ring, counters }
    }

    /// Puts a received byte into the ring; false (and counted) when the ring is full.
    pub fn push(&mut self, b: u8) -> bool {
        let ok = self.ring.enqueue(b).is_ok();
        if ok {
            // Only the producer writes `peak`: a load and a store suffice (no CAS on armv6m).
            let len = u32::try_from(self.ring.len()).unwrap_or(u32::MAX);
            if len > self.counters.peak() {
                self.counters.peak.store(len, Ordering::Relaxed);
            }
        } else {
            count(&self.counters.ring_full);
        }
        ok
    }

    /// Bytes waiting in the ring.
    pub fn len(&self) -> usize {
        self.ring.len()
    }

    /// True when no byte is waiting.
    pub fn is_empty(&self) -> bool {
        self.ring.len() == 0
    }

    /// Counts a receive overrun of the UART.
    pub fn overrun(&mut self) {
        count(&self.counters.overruns);
    }

    /// Counts a byte with a line error.
    pub fn line_error(&mut self) {
        count(&self.counters.line_errors);
    }
}

/// A loss [`RxConsumer::take_error`] reports.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum RxLoss {
    /// The UART overran: bytes were lost before the handler read them.
    Overrun,
    /// The ring was full: bytes were dropped.
    RingFull,
}

impl embedded_io::Error for RxLoss {
    fn kind(&self) -> embedded_io::ErrorKind {
        embedded_io::ErrorKind::Other
    }
}

/// Counts already reported.
#[derive(Debug, Default)]
struct Reported {
    ring_full: u32,
    overruns: u32,
    line_errors: u32,
}

/// How much `counter` grew since `*seen`; updates `*seen`.
fn since_last(counter: &AtomicU32, seen: &mut u32) -> u32 {
    let now = counter.load(Ordering::Relaxed);
    let grew = now.wrapping_sub(*seen);
    *seen = now;
    grew
}

/// The driver's end.
pub struct RxConsumer<'a, const S: usize = RING_SLOTS> {
    ring: Consumer<'a, u8, S>,
    counters: &'a RxCounters,
    reported: Reported,
}

impl<'a, const S: usize> RxConsumer<'a, S> {
    /// The consumer end `ring`, reading losses from `counters`.
    pub fn new(ring: Consumer<'a, u8, S>, counters: &'a RxCounters) -> Self {
        Self {
            ring,
            counters,
            reported: Reported::default(),
        }
    }

    /// New losses since the last call, once: an overrun before a full ring. Line errors are
    /// only logged: they are expected while the driver probes the baud rate, and the damaged
    /// telegram fails its CRC anyway.
    pub fn take_error(&mut self) -> Result<(), RxLoss> {
        let r = &mut self.reported;
        let line_errors = since_last(&self.counters.line_errors, &mut r.line_errors);
        let overruns = since_last(&self.counters.overruns, &mut r.overruns);
        let ring_full = since_last(&self.counters.ring_full, &mut r.ring_full);
        if line_errors > 0 {
            log!(warn, "rx: {} bytes with line errors", line_errors);
        }
        if ring_full > 0 {
            log!(warn, "rx: ring full, {} bytes dropped", ring_full);
        }
        if overruns > 0 {
            Err(RxLoss::Overrun)
        } else if ring_full > 0 {
            Err(RxLoss::RingFull)
        } else {
            Ok(())
        }
    }

    /// The driver's read, without waiting: the bytes in the ring (up to `buf.len()`) first,
    /// and only when none is waiting a new loss ([`RxConsumer::take_error`]). Bytes before a
    /// loss are never held back by it, so a full ring drains even while the wire keeps
    /// overflowing it between reads.
    pub fn read(&mut self, buf: &mut [u8]) -> Result<usize, RxLoss> {
        match self.read_available(buf) {
            0 => self.take_error().map(|()| 0),
            n => Ok(n),
        }
    }

    /// The driver's blocking read: spins until a byte is in the ring (or a loss is
    /// reported), then takes what is there, up to `buf.len()` bytes; `Ok(0)` only for an
    /// empty `buf`. Drivers read after `ready()`, so this hardly ever spins.
    pub fn read_blocking(&mut self, buf: &mut [u8]) -> Result<usize, RxLoss> {
        if buf.is_empty() {
            return Ok(0);
        }
        loop {
            match self.read(buf)? {
                0 => core::hint::spin_loop(),
                n => return Ok(n),
            }
        }
    }

    /// Takes what is in the ring, up to `buf.len()` bytes, without waiting.
    pub fn read_available(&mut self, buf: &mut [u8]) -> usize {
        let mut n = 0;
        for slot in buf {
            let Some(b) = self.ring.dequeue() else { break };
            *slot = b;
            n += 1;
        }
        n
    }

    /// True when a byte is waiting or a loss is not yet reported (so that a driver that
    /// reads only when ready gets it).
    pub fn ready(&self) -> bool {
        self.ring.ready() || self.loss_pending()
    }

    /// True when the ring dropped bytes or the UART overran since the last report.
    pub fn loss_pending(&self) -> bool {
        self.counters.ring_full() != self.reported.ring_full
            || self.counters.overruns() != self.reported.overruns
    }

    /// Bytes waiting.
    pub fn len(&self) -> usize {
        self.ring.len()
    }

    /// True when no byte is waiting.
    pub fn is_empty(&self) -> bool {
        !self.ring.ready()
    }

    /// Discards what is waiting (stale bytes after a baud switch; call with the producer
    /// stopped).
    pub fn clear(&mut self) {
        while self.ring.dequeue().is_some() {}
    }

    /// The loss counters.
    pub fn counters(&self) -> &RxCounters {
        self.counters
    }
}
