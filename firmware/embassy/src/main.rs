//! The pfe firmware on embassy, for the STM32F411 board of `firmware/board` (WeAct "Black
//! Pill" F411CE, 25 MHz crystal, 96 MHz core): the same wiring and output, async.
//!
//! - LMS200 on USART1 (PA9 TX, PA10 RX): received by DMA into a ring buffer
//!   (`RingBufferedUartRx`, DMA2 stream 2), sent by DMA (stream 7), driven by
//!   [`lms2xx::driver::AsyncDriver`] (the blocking driver's state machine: same init, baud
//!   switch, retries, re-initialisation, timeouts and counters) in the `scanner` task.
//! - Each scan goes through a one-slot channel to the `features` task: pfe-core's extractor
//!   and the frame encoder ([`firmware::app::App::process`], `pfe_frame`), one COBS frame per
//!   scan out on USART2 (PA2 TX, DMA1 stream 6) at 460 800 baud. When the features task is
//!   still busy, the scanner waits (the DMA ring keeps receiving meanwhile).
//! - defmt logs over RTT, panics through panic-probe.
//!
//! Build: `cargo build --release --target thumbv7em-none-eabihf` in this directory (its own
//! workspace, so the main workspace never builds embassy).
#![no_std]
#![no_main]
#![forbid(unsafe_code)]

use defmt_rtt as _;
use panic_probe as _;

use embassy_executor::Spawner;
use embassy_stm32::mode::Async;
use embassy_stm32::time::Hertz;
use embassy_stm32::usart::{self, RingBufferedUartRx, UartTx};
use embassy_stm32::{bind_interrupts, dma, peripherals};
use embassy_sync::blocking_mutex::raw::CriticalSectionRawMutex;
use embassy_sync::channel::Channel;
use embassy_time::{Delay, Instant};
use static_cell::{ConstStaticCell, StaticCell};

use firmware::app::{link_counters, ConfigChoice, LmsApp, ScanDataExt, LMS_FEATURES};
use lms2xx::driver::{AsyncDriver, AsyncSetBaud, Clock, Config, Counters, ScanData};

/// Feature output baud rate (as the blocking board firmware).
const OUTPUT_BAUD: u32 = 460_800;
/// DMA ring for the scanner's bytes: 1 KiB is 27 ms at 38 400 Bd, 2 ms at 500 000 Bd of
/// slack for the scanner task (it only decodes; the extraction runs in the other task).
const RX_RING: usize = 1024;
/// Largest frame: header and [`LMS_FEATURES`] features, COBS-stuffed and terminated.
const FRAME_MAX: usize = pfe_frame::max_frame_len(LMS_FEATURES);

bind_interrupts!(struct Irqs {
    USART1 => usart::InterruptHandler<peripherals::USART1>;
    DMA2_STREAM2 => dma::InterruptHandler<peripherals::DMA2_CH2>;
    DMA2_STREAM7 => dma::InterruptHandler<peripherals::DMA2_CH7>;
    DMA1_STREAM6 => dma::InterruptHandler<peripherals::DMA1_CH6>;
});

/// A scan and the driver's counters after it, from the scanner task to the features task.
static SCANS: Channel<CriticalSectionRawMutex, (ScanData, Counters), 1> = Channel::new();

/// The scanner's UART: DMA ring-buffered receive, DMA transmit, one baud rate for both.
struct Scanner {
    rx: RingBufferedUartRx<'static>,
    tx: UartTx<'static, Async>,
}

/// The scanner UART's errors.
#[derive(Clone, Copy, Debug, PartialEq, Eq, defmt::Format)]
enum UartError {
    /// Overrun, framing, noise, parity or a DMA ring overrun.
    Line(usart::Error),
    /// The baud rate cannot be set from the peripheral clock.
    Baud,
}

impl core::fmt::Display for UartError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            UartError::Line(e) => write!(f, "UART line error: {e:?}"),
            UartError::Baud => f.write_str("baud rate out of range"),
        }
    }
}

impl core::error::Error for UartError {}

impl embedded_io_async::Error for UartError {
    fn kind(&self) -> embedded_io_async::ErrorKind {
        embedded_io_async::ErrorKind::Other
    }
}

impl embedded_io_async::ErrorType for Scanner {
    type Error = UartError;
}

impl embedded_io_async::Read for Scanner {
    async fn read(&mut self, buf: &mut [u8]) -> Result<usize, UartError> {
        self.rx.read(buf).await.map_err(UartError::Line)
    }
}

impl embedded_io_async::Write for Scanner {
    async fn write(&mut self, buf: &[u8]) -> Result<usize, UartError> {
        self.tx.write(buf).await.map_err(UartError::Line)?;
        Ok(buf.len())
    }
    async fn flush(&mut self) -> Result<(), UartError> {
        self.tx.flush().await.map_err(UartError::Line)
    }
}

impl AsyncSetBaud for Scanner {
    async fn set_baud(&mut self, baud: u32) -> Result<(), UartError> {
        // The last command's bytes leave before the rate changes (the driver flushed).
        self.tx.set_baudrate(baud).map_err(|_| UartError::Baud)?;
        self.rx.set_baudrate(baud).map_err(|_| UartError::Baud)
    }
}

/// Milliseconds from embassy-time.
struct Millis;

impl Clock for Millis {
    fn now_ms(&mut self) -> u32 {
        // Wraps after 49 days, as the driver expects.
        Instant::now().as_millis() as u32
    }
}

#[embassy_executor::task]
async fn scanner(mut lms: AsyncDriver<Scanner, Delay, Millis>) {
    loop {
        match lms.next_scan().await {
            Ok(scan) => {
                let scan = scan.clone();
                let counters = lms.counters();
                SCANS.send((scan, counters)).await;
            }
            Err(e) => defmt::warn!("scanner: {}", e),
        }
    }
}

#[embassy_executor::task]
async fn features(mut out: UartTx<'static, Async>) {
    // Room for every LMS200 variant (up to 401 values) and 48 features; all zero bytes, so
    // it is in .bss and never copied through the stack.
    static APP: ConstStaticCell<LmsApp> = ConstStaticCell::new(LmsApp::new(ConfigChoice::Default));
    let app = APP.take();
    let mut frame = [0u8; FRAME_MAX];
    loop {
        let (scan, counters) = SCANS.receive().await;
        let mut w: &mut [u8] = &mut frame;
        // Without the pose step: it costs far more than a scan period on the M4F for now
        // (docs/POSE.md, "On the board"); every scan's features first.
        let header = match app.process_features(&scan.raw(), link_counters(&counters), &mut w) {
            Ok(h) => h,
            Err(_) => {
                defmt::warn!("frame larger than its buffer");
                continue;
            }
        };
        let n = FRAME_MAX - w.len();
        match out.write(frame.get(..n).unwrap_or(&[])).await {
            Ok(()) => defmt::debug!("scan {}: {} features", header.seq, header.n_features),
            Err(e) => defmt::warn!("feature output failed: {}", e),
        }
    }
}

#[embassy_executor::main]
async fn main(spawner: Spawner) {
    let mut config = embassy_stm32::Config::default();
    {
        use embassy_stm32::rcc::*;
        // 25 MHz / 25 × 192 / 2 = 96 MHz (the board firmware's clock); 48 MHz on Q.
        config.rcc.hse = Some(Hse {
            freq: Hertz(25_000_000),
            mode: HseMode::Oscillator,
        });
        config.rcc.pll_src = PllSource::HSE;
        config.rcc.pll = Some(Pll {
            prediv: PllPreDiv::DIV25,
            mul: PllMul::MUL192,
            divp: Some(PllPDiv::DIV2),
            divq: Some(PllQDiv::DIV4),
            divr: None,
        });
        config.rcc.ahb_pre = AHBPrescaler::DIV1;
        config.rcc.apb1_pre = APBPrescaler::DIV2;
        config.rcc.apb2_pre = APBPrescaler::DIV1;
        config.rcc.sys = Sysclk::PLL1_P;
    }
    let p = embassy_stm32::init(config);

    let mut out_cfg = usart::Config::default();
    out_cfg.baudrate = OUTPUT_BAUD;
    let Ok(out) = UartTx::new(p.USART2, p.PA2, p.DMA1_CH6, Irqs, out_cfg) else {
        defmt::panic!("USART2 configuration");
    };

    // The LMS200 powers up at 9600 baud; the driver probes and switches.
    let mut lms_cfg = usart::Config::default();
    lms_cfg.baudrate = 9600;
    let Ok(uart) = usart::Uart::new(
        p.USART1, p.PA10, p.PA9, p.DMA2_CH7, p.DMA2_CH2, Irqs, lms_cfg,
    ) else {
        defmt::panic!("USART1 configuration");
    };
    let (tx, rx) = uart.split();
    static RING: StaticCell<[u8; RX_RING]> = StaticCell::new();
    let rx = rx.into_ring_buffered(RING.init([0; RX_RING]));
    let lms = AsyncDriver::new(Scanner { rx, tx }, Delay, Millis, Config::default());

    defmt::info!(
        "pfe-embassy: LMS200 on USART1 (DMA ring), features on USART2 at {} baud",
        OUTPUT_BAUD
    );
    // Each task is spawned once: its pool has room.
    let (Ok(features), Ok(scanner)) = (features(out), scanner(lms)) else {
        defmt::panic!("task spawned twice");
    };
    spawner.spawn(features);
    spawner.spawn(scanner);
}
