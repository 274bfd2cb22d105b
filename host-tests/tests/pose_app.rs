//! The firmware's pose step on the host: the `App` sends in each frame the pose that
//! pfe-pose's feature odometry (`FeatureOdometry::update_features`, the call `pfe odometry`
//! makes) gives for the features it sends, bit for bit, and on a simulated drive around a room
//! (`pfe_eval::scene::drive`) that pose follows the true one.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing
)]

use firmware::app::{pose_block, App, ConfigChoice, RawScan};
use host_tests::qemu::{decode_frames, VecWriter};
use pfe_eval::scene::drive;
use pfe_frame::{PoseBlock, PoseStatus};
use pfe_pose::{FeatureOdometry, Pose};

/// The bits of every number of a pose block.
fn bits(b: &PoseBlock) -> Vec<u32> {
    let mut v = Vec::new();
    for c in [b.rel, b.pose] {
        v.extend([c.x, c.y, c.theta].map(f32::to_bits));
        v.extend(c.cov.iter().flatten().map(|x| x.to_bits()));
    }
    if let PoseStatus::Degenerate { direction } = b.status {
        v.extend(direction.map(f32::to_bits));
    }
    v
}

#[test]
fn the_app_sends_the_odometry_of_its_features_and_it_follows_the_drive() {
    let scans = drive::room_drive(drive::LOOP, 7);
    let mut app = Box::new(App::<361, 48>::new(ConfigChoice::Default));
    let mut odo = Box::new(FeatureOdometry::new_default());
    let truth0 = Pose::new(
        scans[0].pose[0] as f32,
        scans[0].pose[1] as f32,
        scans[0].pose[2] as f32,
    );
    let (mut ok, mut worst) = (0usize, 0.0f32);
    for (k, d) in scans.iter().enumerate() {
        let mut out = VecWriter(Vec::new());
        let scan = RawScan::lms_8m(d.scan.geometry, &d.scan.raw, 1.0);
        app.process(&scan, Default::default(), &mut out).unwrap();
        let (frames, errors) = decode_frames(&out.0);
        assert!(errors.is_empty(), "{errors:?}");
        let frame = &frames[0];
        let sent = frame.pose.expect("a pose block in every scan frame");
        let host = pose_block(&odo.update_features(&frame.features, None));
        assert_eq!(
            bits(&sent),
            bits(&host),
            "scan {k}: board {sent:?}, host {host:?}"
        );
        assert_eq!(sent.status, host.status, "scan {k}");
        if sent.status == PoseStatus::Ok {
            ok += 1;
        }
        // Against the drive's truth: this scan's pose in the first scan's frame.
        let t = truth0.inverse().compose(&Pose::new(
            d.pose[0] as f32,
            d.pose[1] as f32,
            d.pose[2] as f32,
        ));
        let err = (sent.pose.x - t.x).hypot(sent.pose.y - t.y);
        worst = worst.max(err);
        assert!(
            pfe_pose::wrap(sent.pose.theta - t.theta).abs() < 0.05,
            "scan {k}: heading {} vs true {}",
            sent.pose.theta,
            t.theta
        );
    }
    // A loop of 12.9 m: the odometry stays within 0.1 m of the truth (14 mm measured), nearly every scan
    // registered.
    assert!(worst < 100.0, "worst position error {worst} mm");
    assert!(
        ok >= drive::LOOP * 9 / 10,
        "{ok} of {} scans ok",
        drive::LOOP
    );
    eprintln!(
        "drive: {ok}/{} ok, worst position error {worst:.0} mm",
        drive::LOOP
    );
}
