//! The newer CARMEN logger's laser lines, `ROBOTLASER1` and `RAWLASER1`: each with its own
//! start angle, step and maximum range (see the module docs of [`super`]).

use pfe_core::ScanGeometry;

use super::{not_metres, pose, LONG_MAX_RANGE_MM};
use crate::{check_beams, checked_record, number, ranges_mm, InputError, Record};

/// The front laser's messages a CARMEN log may hold, each scan once per kind.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Laser {
    /// `FLASER`: 180° field (see the angle convention), a pose taken as the laser's.
    Flaser,
    /// `ROBOTLASER1`: its own start angle, step and maximum range, the laser's pose.
    RobotLaser1,
    /// `RAWLASER1`: its own start angle, step and maximum range, no pose.
    RawLaser1,
}

impl Laser {
    /// The kind of the message named `name`, if it is one of the front laser's.
    pub(super) fn of(name: &str) -> Option<Self> {
        match name {
            "FLASER" => Some(Self::Flaser),
            "ROBOTLASER1" => Some(Self::RobotLaser1),
            "RAWLASER1" => Some(Self::RawLaser1),
            _ => None,
        }
    }

    /// The message's name.
    pub fn name(self) -> &'static str {
        match self {
            Self::Flaser => "FLASER",
            Self::RobotLaser1 => "ROBOTLASER1",
            Self::RawLaser1 => "RAWLASER1",
        }
    }
}

/// A `ROBOTLASER1` or `RAWLASER1` line: `laser_type start_angle field_of_view
/// angular_resolution maximum_range accuracy remission_mode n r_1 … r_n num_remissions
/// remission_1 … [laser_x laser_y laser_θ robot_x robot_y robot_θ tv rv
/// forward_safety_dist side_safety_dist turn_axis] timestamp host logger_timestamp`.
/// Older `ROBOTLASER1` lines without the remissions (and the turn axis) are read too.
/// `r_max_default`: the maximum range when the line's is not usable.
pub(super) fn read(
    line: u64,
    rest: &str,
    laser: Laser,
    r_max_default: f32,
) -> Result<Record, InputError> {
    let name = laser.name();
    let mut tokens = rest.split_ascii_whitespace();
    let mut header = [0.0f64; 7];
    let what = [
        "laser type",
        "start angle",
        "field of view",
        "angular resolution",
        "maximum range",
        "accuracy",
        "remission mode",
    ];
    for (v, what) in header.iter_mut().zip(what) {
        *v = number(line, what, tokens.next())?;
    }
    let [_, start, fov, step, max, _, _] = header;
    let n: usize = number(line, "beam count", tokens.next())?;
    check_beams(line, n)?;
    // The LMS "8183" no-return code is no return whatever maximum the log states.
    let r_max = if max.is_finite() && max > 0.0 {
        ((max * 1000.0) as f32).min(LONG_MAX_RANGE_MM)
    } else {
        r_max_default
    };
    let ranges = ranges_mm(line, (name, n), &mut tokens, not_metres, |mm| {
        mm > 0.0 && mm < r_max
    })?;
    let rest: Vec<&str> = tokens.collect();
    let tail = laser_tail(line, laser, &rest)?;
    let field = |k: usize| tail.get(k).and_then(|t| t.parse::<f64>().ok());
    // Beams evenly spread over the field when the step is not usable.
    let step = if step.is_finite() && step != 0.0 {
        step
    } else {
        fov / n.saturating_sub(1).max(1) as f64
    };
    let geometry = ScanGeometry::new(start as f32, step as f32, r_max);
    let mut record = checked_record(line, 0, geometry, ranges)?;
    // CARMEN's laser types: 0 a SICK LMS, 1 a SICK PLS, 2 a Hokuyo URG, 3 simulated, 4 a
    // SICK S300 (5 and 6, in some versions, a laser emulated from a Kinect or a stereo
    // camera), 99 unknown. Only an LMS interleaves sweeps.
    if (2.0..=6.0).contains(&header[0]) {
        record.sweeps = Some(1);
    }
    if laser == Laser::RobotLaser1 {
        record.pose = pose([field(0), field(1), field(2)]);
    }
    // The timestamp is third from the end (then the host and the logger's timestamp).
    record.time = tail
        .len()
        .checked_sub(3)
        .and_then(field)
        .filter(|t| t.is_finite());
    Ok(record)
}

/// The fields of a `ROBOTLASER1` or `RAWLASER1` line after its ranges, past the remissions:
/// for `RAWLASER1` the timestamp, host and logger timestamp; for `ROBOTLASER1` the laser's and
/// the robot's pose, tv rv and the two safety distances, with or without the turn axis, then
/// those three. The remissions (a count, then that many values) are told apart from an older
/// `ROBOTLASER1` line without them by the number of fields.
fn laser_tail<'a>(
    line: u64,
    laser: Laser,
    rest: &'a [&'a str],
) -> Result<&'a [&'a str], InputError> {
    let name = laser.name();
    let after: &[usize] = match laser {
        Laser::RobotLaser1 => &[13, 14],
        _ => &[3],
    };
    let count = rest
        .first()
        .filter(|t| t.bytes().all(|b| b.is_ascii_digit()))
        .and_then(|t| t.parse::<usize>().ok());
    if let Some(m) = count {
        let tail = rest.get(1..).and_then(|r| r.get(m.min(r.len())..));
        if let Some(tail) = tail.filter(|t| m < rest.len() && after.contains(&t.len())) {
            return Ok(tail);
        }
    }
    if laser == Laser::RobotLaser1 && after.contains(&rest.len()) {
        return Ok(rest);
    }
    let expected = match laser {
        Laser::RobotLaser1 => {
            "the remission count, the remissions and 13 or 14 fields (two poses, \
            tv rv, the safety distances, the turn axis or not, timestamp host logger_timestamp)"
        }
        _ => "the remission count, the remissions, timestamp host logger_timestamp",
    };
    Err(InputError::line(
        line,
        format!(
            "{name}: {} fields after the ranges; expected {expected}",
            rest.len()
        ),
    ))
}
