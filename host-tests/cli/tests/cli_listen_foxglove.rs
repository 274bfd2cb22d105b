//! `pfe listen --mcap` read back by an independent reader (`fixtures/foxglove/read_foxglove.py`,
//! the PyPI `mcap` package), and `pfe listen --foxglove` received by a WebSocket client
//! (tungstenite's client side) speaking `foxglove.websocket.v1`.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)]

#[path = "../../tests/common/mod.rs"]
mod common;
use common::{arg, scratch};
use std::io::{BufRead, BufReader, Write};
use std::net::TcpStream;
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, SystemTime, UNIX_EPOCH};

use pfe_cli::foxglove::{scene_update, FEATURES_TOPIC};
use pfe_core::{CircleFeature, Feature, LineFeature, Point};
use pfe_frame::{write_scan, ScanHeader};
use pfe_testkit::qemu::VecWriter;
use serde_json::{json, Value};
use tungstenite::client::IntoClientRequest;
use tungstenite::Message;

/// Scan `k`: a line, and from the second scan on a circle; firmware times 133 ms apart
/// starting just before the u32 wrap.
fn scan(k: u32) -> (u32, Vec<Feature>) {
    let mut f = vec![Feature::Line(LineFeature::new(
        3,
        40,
        38,
        0.25 + 0.01 * k as f32,
        1500.0 + k as f32,
        1e-6,
        2.0,
        1e-5,
        Point::new(1400.0, -200.0),
        Point::new(1300.0, 400.0),
    ))];
    if k > 0 {
        f.push(Feature::Circle(CircleFeature::new(
            100,
            120,
            21,
            Point::new(800.0, 900.0 + k as f32),
            150.0,
            [[4.0, 1.0, 0.5], [1.0, 9.0, 0.25], [0.5, 0.25, 1.0]],
            0.5,
            1.0,
        )));
    }
    ((u32::MAX - 200).wrapping_add(133 * k), f)
}

fn frames(n: u32) -> Vec<u8> {
    let mut w = VecWriter(Vec::new());
    for k in 0..n {
        let (time_ms, features) = scan(k);
        let h = ScanHeader {
            seq: k,
            time_ms,
            ..ScanHeader::default()
        };
        write_scan(&mut w, &h, &features).unwrap();
    }
    w.0
}

fn now_ns() -> u64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .unwrap()
        .as_nanos() as u64
}

fn pfe(args: &[&str], input: &Path) -> (i32, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_pfe"))
        .args(["listen", "--input"])
        .arg(input)
        .args(args)
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn read_back(path: &Path) -> Option<Value> {
    common::read_foxglove(
        "cli_listen_foxglove::listen_mcap_reads_back_message_for_message",
        path,
    )
}

fn near(v: &Value, expected: f64) -> bool {
    (v.as_f64().unwrap() - expected).abs() <= 1e-12 * (1.0 + expected.abs())
}

/// Checks one SceneUpdate against scan `k`, stamped `stamp` ns.
fn check_scene(d: &Value, k: u32, stamp: u64) {
    let (_, features) = scan(k);
    let t = json!({ "sec": stamp / 1_000_000_000, "nsec": stamp % 1_000_000_000 });
    assert_eq!(d["deletions"][0]["type"], 1);
    assert_eq!(d["deletions"][0]["timestamp"], t);
    let entities = d["entities"].as_array().unwrap();
    assert_eq!(entities.len(), features.len(), "scan {k}");
    for (j, (e, f)) in entities.iter().zip(&features).enumerate() {
        assert_eq!(e["id"], format!("feature-{j}"));
        assert_eq!((&e["timestamp"], &e["frame_id"]), (&t, &json!("laser")));
        let meta = |key: &str| common::metadata(e, key);
        assert_eq!(meta("first"), f.first().to_string());
        assert_eq!(meta("last"), f.last().to_string());
        match f {
            Feature::Line(l) => {
                assert_eq!(meta("kind"), "line");
                assert_eq!(meta("rho_mm").parse::<f32>().unwrap(), l.rho);
                assert_eq!(meta("alpha_rad").parse::<f32>().unwrap(), l.alpha);
                let seg = &e["lines"][0]["points"];
                assert!(near(&seg[0]["x"], f64::from(l.start.x) * 1e-3));
                assert!(near(&seg[1]["y"], f64::from(l.end.y) * 1e-3));
            }
            Feature::Circle(c) => {
                assert_eq!(meta("kind"), "circle");
                assert_eq!(meta("radius_mm").parse::<f32>().unwrap(), c.radius);
                assert_eq!(meta("center_y_mm").parse::<f32>().unwrap(), c.center.y);
                let p = &e["cylinders"][0]["pose"]["position"];
                assert!(near(&p["x"], f64::from(c.center.x) * 1e-3));
                assert_eq!(meta("sigma_radius_mm").parse::<f64>().unwrap(), 1.0);
            }
            _ => {}
        }
    }
    // And the whole message is what the shared scene code makes of the features (both through
    // the same JSON parser, which is not exact to the last bit).
    let expected: Value =
        serde_json::from_str(&scene_update(stamp, "laser", &features).to_string()).unwrap();
    assert_eq!(*d, expected);
}

#[test]
fn listen_mcap_reads_back_message_for_message() {
    let d = scratch("mcap");
    let input = d.join("frames.bin");
    let n = 6;
    std::fs::write(&input, frames(n)).unwrap();
    let out = d.join("out.mcap");
    let before = now_ns();
    let (code, err) = pfe(&["--mcap", arg(&out)], &input);
    let after = now_ns();
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("wrote"), "{err}");
    // Never over an existing file without --force; --force replaces it; --scans ends early
    // with a complete file.
    let (code, err) = pfe(&["--mcap", arg(&out)], &input);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("--force"), "{err}");
    let short = d.join("short.mcap");
    std::fs::write(&short, b"mine").unwrap();
    let (code, err) = pfe(&["--mcap", arg(&short), "--scans", "2"], &input);
    assert_eq!(
        (code, std::fs::read(&short).unwrap()),
        (2, b"mine".to_vec()),
        "{err}"
    );
    let args = ["--mcap", arg(&short), "--force", "--scans", "2"];
    assert_eq!(pfe(&args, &input).0, 0);

    let Some(back) = read_back(&out) else {
        std::fs::remove_dir_all(&d).unwrap();
        return;
    };
    let short_back = read_back(&short).unwrap();
    std::fs::remove_dir_all(&d).unwrap();
    assert_eq!(short_back["messages"].as_array().unwrap().len(), 2);

    // Only the features: the frames carry no ranges.
    let channels = back["channels"].as_array().unwrap();
    assert_eq!(channels.len(), 1);
    assert_eq!(channels[0]["topic"], FEATURES_TOPIC);
    assert_eq!(channels[0]["schema"], "foxglove.SceneUpdate");
    assert_eq!(channels[0]["schema_encoding"], "jsonschema");
    assert_eq!(channels[0]["schema_is_json"], true);
    let messages = back["messages"].as_array().unwrap();
    assert_eq!(messages.len(), n as usize);
    assert_eq!(back["statistics"]["message_count"], n);
    let publish0 = messages[0]["publish_time"].as_u64().unwrap();
    for (k, m) in messages.iter().enumerate() {
        let k = k as u32;
        assert_eq!(m["topic"], FEATURES_TOPIC);
        assert_eq!(m["sequence"], k);
        // Log time: when it was received; publish time (and the message's stamps): the
        // firmware's time, 133 ms apart across the u32 wrap, anchored at the first receive.
        let log = m["log_time"].as_u64().unwrap();
        assert!(
            (before..=after).contains(&log),
            "{log} not in {before}..{after}"
        );
        let publish = m["publish_time"].as_u64().unwrap();
        assert_eq!(publish - publish0, u64::from(k) * 133_000_000);
        assert_eq!(Some(publish0), messages[0]["log_time"].as_u64());
        check_scene(&m["data"], k, publish);
    }
}

/// Reads text messages until one with `op`.
fn expect_op(ws: &mut tungstenite::WebSocket<TcpStream>, op: &str) -> Value {
    loop {
        if let Message::Text(t) = ws.read().unwrap() {
            let v: Value = serde_json::from_str(t.as_str()).unwrap();
            if v["op"] == op {
                return v;
            }
        }
    }
}

fn connect(
    addr: &str,
    subprotocol: Option<&str>,
) -> Result<tungstenite::WebSocket<TcpStream>, String> {
    let mut req = format!("ws://{addr}/").into_client_request().unwrap();
    if let Some(p) = subprotocol {
        req.headers_mut()
            .insert("Sec-WebSocket-Protocol", p.parse().unwrap());
    }
    let stream = TcpStream::connect(addr).unwrap();
    stream
        .set_read_timeout(Some(Duration::from_secs(20)))
        .unwrap();
    tungstenite::client(req, stream)
        .map(|(ws, resp)| {
            assert_eq!(
                resp.headers()["Sec-WebSocket-Protocol"],
                "foxglove.websocket.v1"
            );
            ws
        })
        .map_err(|e| e.to_string())
}

#[test]
fn listen_foxglove_serves_the_scans_it_was_fed() {
    let mut child = Command::new(env!("CARGO_BIN_EXE_pfe"))
        .args([
            "listen",
            "--input",
            "-",
            "--foxglove",
            "--bind",
            "127.0.0.1:0",
        ])
        .stdin(Stdio::piped())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut stderr = BufReader::new(child.stderr.take().unwrap());
    let mut line = String::new();
    let addr = loop {
        line.clear();
        assert!(
            stderr.read_line(&mut line).unwrap() > 0,
            "no address printed"
        );
        if let Some(a) = line.trim().split("ws://").nth(1) {
            break a.to_string();
        }
    };
    assert!(addr.starts_with("127.0.0.1:"), "{addr}");

    // Without Foxglove's subprotocol: refused.
    assert!(connect(&addr, None).is_err());

    let mut ws = connect(&addr, Some("foxglove.websocket.v1")).unwrap();
    let info = expect_op(&mut ws, "serverInfo");
    assert_eq!(info["capabilities"], json!([]));
    let adv = expect_op(&mut ws, "advertise");
    let channels = adv["channels"].as_array().unwrap();
    assert_eq!(channels.len(), 1);
    let c = &channels[0];
    assert_eq!(
        (
            &c["topic"],
            &c["encoding"],
            &c["schemaName"],
            &c["schemaEncoding"]
        ),
        (
            &json!(FEATURES_TOPIC),
            &json!("json"),
            &json!("foxglove.SceneUpdate"),
            &json!("jsonschema")
        )
    );
    let schema: Value = serde_json::from_str(c["schema"].as_str().unwrap()).unwrap();
    assert_eq!(schema["title"], "foxglove.SceneUpdate");
    // Subscribe twice (ids 7 and 9), drop 9; a ping's pong says the server has read them.
    let sub = json!({ "op": "subscribe", "subscriptions": [
        { "id": 7, "channelId": c["id"] }, { "id": 9, "channelId": c["id"] }] });
    ws.send(Message::text(sub.to_string())).unwrap();
    let unsub = json!({ "op": "unsubscribe", "subscriptionIds": [9] });
    ws.send(Message::text(unsub.to_string())).unwrap();
    ws.send(Message::Ping(Vec::new().into())).unwrap();
    while !matches!(ws.read().unwrap(), Message::Pong(_)) {}

    let n = 5;
    let before = now_ns();
    let mut stdin = child.stdin.take().unwrap();
    stdin.write_all(&frames(n)).unwrap();
    drop(stdin);
    let mut got = Vec::new();
    loop {
        match ws.read() {
            Ok(Message::Binary(b)) => got.push(b.to_vec()),
            Ok(Message::Close(_)) | Err(tungstenite::Error::ConnectionClosed) => break,
            Ok(_) => {}
            Err(e) => panic!("{e}"),
        }
    }
    let after = now_ns();
    assert!(child.wait().unwrap().success());
    assert_eq!(got.len(), n as usize);
    let mut stamp0 = 0;
    for (k, b) in got.iter().enumerate() {
        assert_eq!(b[0], 0x01);
        assert_eq!(u32::from_le_bytes(b[1..5].try_into().unwrap()), 7);
        let log = u64::from_le_bytes(b[5..13].try_into().unwrap());
        assert!((before..=after).contains(&log));
        let d: Value = serde_json::from_slice(&b[13..]).unwrap();
        let t = &d["deletions"][0]["timestamp"];
        let stamp = t["sec"].as_u64().unwrap() * 1_000_000_000 + t["nsec"].as_u64().unwrap();
        if k == 0 {
            stamp0 = stamp;
        }
        assert_eq!(stamp - stamp0, k as u64 * 133_000_000);
        check_scene(&d, k as u32, stamp);
    }
}

/// Feeds 3 scans on stdin and keeps it open; `stop` ends `pfe listen` (a signal, or nothing
/// when --seconds does it); returns the messages of the file.
fn mcap_after(tag: &str, extra: &[&str], stop: impl FnOnce(u32)) -> Option<Vec<Value>> {
    let d = scratch(tag);
    let out = d.join("out.mcap");
    let mut child = Command::new(env!("CARGO_BIN_EXE_pfe"))
        .args(["listen", "--input", "-", "--mcap"])
        .arg(&out)
        .args(extra)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut stdin = child.stdin.take().unwrap();
    stdin.write_all(&frames(3)).unwrap();
    stdin.flush().unwrap();
    let mut stdout = BufReader::new(child.stdout.take().unwrap());
    for _ in 0..3 {
        let mut line = String::new();
        assert!(stdout.read_line(&mut line).unwrap() > 0);
    }
    stop(child.id());
    let status = child.wait().unwrap();
    drop(stdin);
    let mut err = String::new();
    std::io::Read::read_to_string(&mut child.stderr.take().unwrap(), &mut err).unwrap();
    assert!(status.success(), "{err}");
    let back = read_back(&out);
    std::fs::remove_dir_all(&d).unwrap();
    back.map(|b| b["messages"].as_array().unwrap().clone())
}

#[test]
fn listen_mcap_is_complete_after_ctrl_c_and_seconds() {
    let interrupt = |pid: u32| {
        let ok = Command::new("kill")
            .args(["-INT", &pid.to_string()])
            .status()
            .unwrap();
        assert!(ok.success());
    };
    let Some(m) = mcap_after("sigint", &[], interrupt) else {
        return;
    };
    assert_eq!(m.len(), 3);
    let m = mcap_after("seconds", &["--seconds", "2"], |_| {}).unwrap();
    assert_eq!(m.len(), 3);
    check_scene(&m[2]["data"], 2, m[2]["publish_time"].as_u64().unwrap());
}
