//! [`FoxgloveServer`]: Foxglove's WebSocket protocol (`foxglove.websocket.v1`), server side,
//! over the sync `tungstenite` crate with one thread per client.
//!
//! On connection the server sends `serverInfo` (no optional capabilities) and one `advertise`
//! of its channels (JSON messages, `jsonschema` schemas). A client's `subscribe` maps its
//! subscription ids to channels, `unsubscribe` (`subscriptionIds`) removes them; every message
//! published on a channel goes to each subscription of it as a binary `messageData`: opcode
//! 0x01, subscription id (u32 LE), log time (u64 LE, ns), payload. A client that falls
//! [`QUEUE`] messages behind loses messages (counted) rather than stalling the publisher.
//!
//! Hand-written over sync `tungstenite` rather than the `foxglove` SDK crate: `pfe` has no
//! async runtime, and the SDK's server brings tokio and about 80 more crates for the few
//! messages used here.

use std::collections::HashMap;
use std::io;
use std::net::{SocketAddr, TcpListener, TcpStream, ToSocketAddrs};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::mpsc::{self, Receiver, SyncSender, TrySendError};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use serde_json::{json, Value};
use tungstenite::handshake::server::{ErrorResponse, Request, Response};
use tungstenite::http::{HeaderValue, StatusCode};
use tungstenite::{HandshakeError, Message, WebSocket};

use super::schema::{Channel, MESSAGE_ENCODING, SCHEMA_ENCODING};

/// The WebSocket subprotocol of Foxglove's protocol v1.
pub const SUBPROTOCOL: &str = "foxglove.websocket.v1";
/// Opcode of a server's binary `messageData`.
pub const MESSAGE_DATA: u8 = 0x01;
/// Messages a client may fall behind before it loses some.
pub const QUEUE: usize = 256;

/// How often the accept loop and the client loops look at the stop flag.
const POLL: Duration = Duration::from_millis(20);
/// Time a client has to complete its handshake.
const HANDSHAKE: Duration = Duration::from_secs(5);
/// A client that takes longer than this to accept a write is dropped.
const WRITE_TIMEOUT: Duration = Duration::from_secs(2);

/// One published message: channel index, log time (ns) and payload.
type Outgoing = Arc<(usize, u64, Vec<u8>)>;

struct Shared {
    stop: AtomicBool,
    clients: Mutex<Vec<SyncSender<Outgoing>>>,
    dropped: AtomicU64,
    threads: Mutex<Vec<JoinHandle<()>>>,
}

/// A Foxglove WebSocket server publishing on fixed channels (ids 1, 2, … in order).
pub struct FoxgloveServer {
    addr: SocketAddr,
    shared: Arc<Shared>,
    accept: Option<JoinHandle<()>>,
}

impl FoxgloveServer {
    /// Binds `addr` (port 0 picks a free port) and serves `channels` from a thread.
    pub fn bind(addr: impl ToSocketAddrs, name: &str, channels: &[Channel]) -> io::Result<Self> {
        let listener = TcpListener::bind(addr)?;
        listener.set_nonblocking(true)?;
        let addr = listener.local_addr()?;
        let shared = Arc::new(Shared {
            stop: AtomicBool::new(false),
            clients: Mutex::new(Vec::new()),
            dropped: AtomicU64::new(0),
            threads: Mutex::new(Vec::new()),
        });
        let hello = Arc::new(hello(name, channels));
        let s = shared.clone();
        let accept = std::thread::spawn(move || accept_loop(&listener, &s, &hello));
        Ok(Self {
            addr,
            shared,
            accept: Some(accept),
        })
    }

    /// The address it listens on.
    pub fn local_addr(&self) -> SocketAddr {
        self.addr
    }

    /// Sends `payload` to every subscription of channel `channel` (an index into the channels
    /// given to [`Self::bind`]), logged at `log_time_ns`.
    pub fn publish(&self, channel: usize, log_time_ns: u64, payload: Vec<u8>) {
        let msg: Outgoing = Arc::new((channel, log_time_ns, payload));
        let Ok(mut clients) = self.shared.clients.lock() else {
            return;
        };
        clients.retain(|c| match c.try_send(msg.clone()) {
            Ok(()) => true,
            Err(TrySendError::Full(_)) => {
                self.shared.dropped.fetch_add(1, Ordering::Relaxed);
                true
            }
            Err(TrySendError::Disconnected(_)) => false,
        });
    }

    /// Messages lost to clients that fell behind.
    pub fn dropped(&self) -> u64 {
        self.shared.dropped.load(Ordering::Relaxed)
    }

    /// Stops accepting, lets each client receive what was published, closes the connections and joins the threads.
    pub fn finish(mut self) {
        self.stop();
    }

    fn stop(&mut self) {
        self.shared.stop.store(true, Ordering::SeqCst);
        if let Some(a) = self.accept.take() {
            let _ = a.join();
        }
        let threads = self
            .shared
            .threads
            .lock()
            .map(|mut t| std::mem::take(&mut *t))
            .unwrap_or_default();
        for t in threads {
            let _ = t.join();
        }
    }
}

impl Drop for FoxgloveServer {
    fn drop(&mut self) {
        self.stop();
    }
}

/// The `serverInfo` and `advertise` messages every client gets first.
fn hello(name: &str, channels: &[Channel]) -> [String; 2] {
    let session = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_nanos());
    let info = json!({
        "op": "serverInfo",
        "name": name,
        "capabilities": [],
        "metadata": {},
        "sessionId": format!("{}-{session}", std::process::id()),
    });
    let advertised: Vec<Value> = channels
        .iter()
        .enumerate()
        .map(|(k, c)| {
            json!({
                "id": k + 1,
                "topic": c.topic,
                "encoding": MESSAGE_ENCODING,
                "schemaName": c.schema_name,
                "schema": String::from_utf8_lossy(&c.schema()),
                "schemaEncoding": SCHEMA_ENCODING,
            })
        })
        .collect();
    let advertise = json!({ "op": "advertise", "channels": advertised });
    [info.to_string(), advertise.to_string()]
}

fn accept_loop(listener: &TcpListener, shared: &Arc<Shared>, hello: &Arc<[String; 2]>) {
    while !shared.stop.load(Ordering::SeqCst) {
        match listener.accept() {
            Ok((stream, _)) => {
                let (tx, rx) = mpsc::sync_channel(QUEUE);
                if let Ok(mut c) = shared.clients.lock() {
                    c.push(tx);
                }
                let (s, h) = (shared.clone(), hello.clone());
                let t = std::thread::spawn(move || {
                    if let Err(e) = serve(stream, &s, &h, &rx) {
                        eprintln!("pfe listen: foxglove client: {e}");
                    }
                });
                if let Ok(mut threads) = shared.threads.lock() {
                    threads.push(t);
                }
            }
            Err(e) if e.kind() == io::ErrorKind::WouldBlock => std::thread::sleep(POLL),
            Err(e) => {
                eprintln!("pfe listen: foxglove server: {e}");
                std::thread::sleep(POLL);
            }
        }
    }
}

/// Accepts the handshake only with Foxglove's subprotocol, and selects it.
#[allow(clippy::result_large_err)] // the signature of tungstenite's handshake callback
fn select_subprotocol(req: &Request, mut resp: Response) -> Result<Response, ErrorResponse> {
    let offered = req
        .headers()
        .get_all("Sec-WebSocket-Protocol")
        .iter()
        .filter_map(|v| v.to_str().ok())
        .flat_map(|v| v.split(','))
        .any(|p| p.trim() == SUBPROTOCOL);
    if !offered {
        let mut e = ErrorResponse::new(Some(format!("subprotocol {SUBPROTOCOL} required")));
        *e.status_mut() = StatusCode::BAD_REQUEST;
        return Err(e);
    }
    resp.headers_mut().insert(
        "Sec-WebSocket-Protocol",
        HeaderValue::from_static(SUBPROTOCOL),
    );
    Ok(resp)
}

fn is_timeout(e: &tungstenite::Error) -> bool {
    matches!(e, tungstenite::Error::Io(e)
        if matches!(e.kind(), io::ErrorKind::WouldBlock | io::ErrorKind::TimedOut))
}

fn handshake(stream: TcpStream) -> Result<WebSocket<TcpStream>, String> {
    stream.set_nonblocking(false).map_err(|e| e.to_string())?;
    stream
        .set_read_timeout(Some(POLL))
        .and_then(|()| stream.set_write_timeout(Some(WRITE_TIMEOUT)))
        .map_err(|e| e.to_string())?;
    let deadline = Instant::now() + HANDSHAKE;
    let mut attempt = tungstenite::accept_hdr(stream, select_subprotocol);
    loop {
        match attempt {
            Ok(ws) => return Ok(ws),
            Err(HandshakeError::Interrupted(mid)) if Instant::now() < deadline => {
                attempt = mid.handshake();
            }
            Err(HandshakeError::Interrupted(_)) => return Err("handshake timed out".into()),
            Err(HandshakeError::Failure(e)) => return Err(format!("handshake: {e}")),
        }
    }
}

/// `messageData`: opcode, subscription id, log time, payload.
pub fn message_data(subscription: u32, log_time_ns: u64, payload: &[u8]) -> Vec<u8> {
    let mut b = Vec::with_capacity(13 + payload.len());
    b.push(MESSAGE_DATA);
    b.extend_from_slice(&subscription.to_le_bytes());
    b.extend_from_slice(&log_time_ns.to_le_bytes());
    b.extend_from_slice(payload);
    b
}

/// Applies a client's text message to its subscriptions (subscription id → channel index).
fn on_text(text: &str, subs: &mut HashMap<u32, usize>, channels: usize) {
    let Ok(v) = serde_json::from_str::<Value>(text) else {
        return;
    };
    match v["op"].as_str() {
        Some("subscribe") => {
            for s in v["subscriptions"].as_array().into_iter().flatten() {
                let id = s["id"].as_u64().and_then(|i| u32::try_from(i).ok());
                let channel = s["channelId"]
                    .as_u64()
                    .and_then(|c| usize::try_from(c).ok())
                    .filter(|&c| (1..=channels).contains(&c));
                if let (Some(id), Some(c)) = (id, channel) {
                    subs.entry(id).or_insert(c - 1);
                }
            }
        }
        Some("unsubscribe") => {
            for id in v["subscriptionIds"].as_array().into_iter().flatten() {
                if let Some(id) = id.as_u64().and_then(|i| u32::try_from(i).ok()) {
                    subs.remove(&id);
                }
            }
        }
        _ => {}
    }
}

fn serve(
    stream: TcpStream,
    shared: &Shared,
    hello: &[String; 2],
    rx: &Receiver<Outgoing>,
) -> Result<(), String> {
    let mut ws = handshake(stream)?;
    let err = |e: tungstenite::Error| e.to_string();
    for h in hello {
        ws.send(Message::text(h.as_str())).map_err(err)?;
    }
    let channels = serde_json::from_str::<Value>(&hello[1])
        .ok()
        .and_then(|v| v["channels"].as_array().map(Vec::len))
        .unwrap_or(0);
    let mut subs: HashMap<u32, usize> = HashMap::new();
    loop {
        match ws.read() {
            Ok(Message::Text(t)) => on_text(t.as_str(), &mut subs, channels),
            Ok(Message::Close(_)) | Err(tungstenite::Error::ConnectionClosed) => return Ok(()),
            Ok(_) => {}
            Err(e) if is_timeout(&e) => {}
            Err(e) => return Err(err(e)),
        }
        // Everything published before the stop is in the queue when it is seen: drain, close.
        let stopping = shared.stop.load(Ordering::SeqCst);
        let mut sent = false;
        while let Ok(msg) = rx.try_recv() {
            let (channel, log_time, payload) = &*msg;
            for (&id, _) in subs.iter().filter(|(_, &c)| c == *channel) {
                ws.write(Message::binary(message_data(id, *log_time, payload)))
                    .map_err(err)?;
                sent = true;
            }
        }
        if sent {
            ws.flush().map_err(err)?;
        }
        if stopping {
            let _ = ws.close(None);
            let _ = ws.flush();
            return Ok(());
        }
    }
}
