//! The 5-axis post: a tool-tip path with its tool axis written as an APT CL file (`MULTAX`,
//! `GOTO/x,y,z,i,j,k`) and as LinuxCNC G-code for a table-tilting A/C machine (the
//! `xyzac-trt` kinematics of LinuxCNC's `trtfuncs.c`), with the kinematics both ways.
//!
//! The G-code is in tool-centre-point form: X Y Z are the tip in the part frame and A C the
//! table's angles, which LinuxCNC turns into joints with the kinematics loaded. The axis
//! (i, j, k) = (sin C sin A, cos C sin A, cos A) gives A = atan2(√(i² + j²), k) and C = atan2(i, j),
//! or the other branch (−A, C + 180°); [`ac_of_axis`] takes the branch within the machine's A
//! limits nearest the previous C, and unwraps C so that it never jumps by more than 180° from
//! one move to the next (at A = 0, where C is free, C stays where it was).

use super::{num, writable};
use crate::error::{Error, Result};
use crate::geom::DVec3;
use crate::model::five::{CutterKind, FiveTool, Machine};

/// One move of a 5-axis path: to the tool tip `tip` with the unit tool axis `axis` (from the
/// tip towards the spindle), a rapid or a feed move at `feed` mm/min.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AxisMove {
    /// The tool tip (the centre of a flat tool's bottom, the lowest point of a ball).
    pub tip: DVec3,
    /// The unit tool axis.
    pub axis: DVec3,
    /// A rapid move.
    pub rapid: bool,
    /// The feed of a cutting move, mm/min.
    pub feed: f64,
}

/// Decimals of coordinates and of the axis' components in the CL file.
const CL_COORD: usize = 4;
const CL_AXIS: usize = 7;

/// The CL file of `moves` for the part `name` cut with `tool`.
pub fn write_cl(name: &str, tool: &FiveTool, moves: &[AxisMove]) -> Result<String> {
    check(moves)?;
    let mut out = String::new();
    out.push_str("$$ swarf five-axis pocketing\n");
    out.push_str(&format!("PARTNO/{}\n", name.replace("$$", "$ $")));
    out.push_str("UNITS/MM\nMULTAX/ON\n");
    // APT's CUTTER/d, r, e, f, a, b, h: the corner's centre offsets, the taper (b) and height
    let r = tool.corner_radius;
    let (e, f) = match tool.kind {
        CutterKind::Ball => (0.0, r),
        _ => (0.5 * tool.diameter - r, r),
    };
    out.push_str(&format!(
        "CUTTER/{},{},{},{},0,{},{}\n",
        num(tool.diameter, 4),
        num(r, 4),
        num(e, 4),
        num(f, 4),
        num(tool.taper_deg, 4),
        num(tool.flute_length, 4)
    ));
    let mut feed = None;
    for m in moves {
        if m.rapid {
            out.push_str("RAPID\n");
        } else if feed != Some(m.feed) {
            out.push_str(&format!("FEDRAT/{},MMPM\n", num(m.feed, 1)));
            feed = Some(m.feed);
        }
        let a = m.axis.normalize();
        out.push_str(&format!(
            "GOTO/{},{},{},{},{},{}\n",
            num(m.tip.x, CL_COORD),
            num(m.tip.y, CL_COORD),
            num(m.tip.z, CL_COORD),
            num(a.x, CL_AXIS),
            num(a.y, CL_AXIS),
            num(a.z, CL_AXIS)
        ));
    }
    out.push_str("FINI\n");
    Ok(out)
}

/// Every number finite and writable, every axis a direction, every feed positive.
fn check(moves: &[AxisMove]) -> Result<()> {
    for (k, m) in moves.iter().enumerate() {
        if !(m.tip.to_array().iter().all(|v| writable(*v)) && m.axis.is_finite() && m.axis.length() > 1e-9) {
            return Err(Error::job("five-axis post", format!("move {k}: a tip or axis that cannot be written")));
        }
        let feed_ok = writable(m.feed) && m.feed > 0.0;
        if !(m.rapid || feed_ok) {
            return Err(Error::job("five-axis post", format!("move {k}: feed {} cannot be written", m.feed)));
        }
    }
    Ok(())
}

/// The tool axis of table angles `a`, `c` (degrees).
pub fn axis_of_ac(a: f64, c: f64) -> DVec3 {
    let (a, c) = (a.to_radians(), c.to_radians());
    DVec3::new(c.sin() * a.sin(), c.cos() * a.sin(), a.cos())
}

/// Table angles (A, C) in degrees for the unit `axis`: of the two branches, those with A within
/// the machine's limits, the one whose C is nearest `c_prev` (C unwrapped to within 180° of
/// it); `None` when neither branch is within the limits.
pub fn ac_of_axis(axis: DVec3, c_prev: f64, machine: &Machine) -> Option<(f64, f64)> {
    let v = axis.normalize();
    let a = v.x.hypot(v.y).atan2(v.z).to_degrees();
    // at A = 0 (the axis vertical) C is free: keep it
    let c0 = if v.x.hypot(v.y) < 1e-12 { c_prev } else { v.x.atan2(v.y).to_degrees() };
    let near = |c: f64| c_prev + (c - c_prev + 180.0).rem_euclid(360.0) - 180.0;
    [(a, near(c0)), (-a, near(c0 + 180.0))]
        .into_iter()
        .filter(|(a, _)| *a >= machine.a_min - 1e-9 && *a <= machine.a_max + 1e-9)
        .min_by(|x, y| (x.1 - c_prev).abs().total_cmp(&(y.1 - c_prev).abs()))
}

/// The joints (X, Y, Z) that put the tip at `tip` (part frame) with the table at `a`, `c`
/// (degrees): `xyzacKinematicsInverse`.
pub fn trt_inverse(tip: DVec3, a: f64, c: f64, m: &Machine) -> DVec3 {
    let (sa, ca) = a.to_radians().sin_cos();
    let (sc, cc) = c.to_radians().sin_cos();
    let (dy, dz) = (m.y_offset, m.z_offset + m.tool_offset);
    let (x, y, z) = (tip.x - m.x_rot_point, tip.y - m.y_rot_point, tip.z - m.z_rot_point);
    DVec3::new(
        cc * x - sc * y + m.x_rot_point,
        sc * ca * x + cc * ca * y - sa * z - ca * dy + sa * dz + dy + m.y_rot_point,
        sc * sa * x + cc * sa * y + ca * z - sa * dy - ca * dz + dz + m.z_rot_point,
    )
}

/// The tip in the part frame of joints `j` with the table at `a`, `c` (degrees):
/// `xyzacKinematicsForward`.
pub fn trt_forward(j: DVec3, a: f64, c: f64, m: &Machine) -> DVec3 {
    let (sa, ca) = a.to_radians().sin_cos();
    let (sc, cc) = c.to_radians().sin_cos();
    let (dy, dz) = (m.y_offset, m.z_offset + m.tool_offset);
    let (x, y, z) = (j.x - m.x_rot_point, j.y - dy - m.y_rot_point, j.z - dz - m.z_rot_point);
    DVec3::new(
        cc * x + sc * ca * y + sc * sa * z + sc * dy + m.x_rot_point,
        -sc * x + cc * ca * y + cc * sa * z + cc * dy + m.y_rot_point,
        -sa * y + ca * z + dz + m.z_rot_point,
    )
}

/// LinuxCNC G-code of `moves` for `machine` (tool-centre-point form, G94): one motion line per
/// move, G0 for rapids and G1 for cuts, every word given at the first motion. Refused when an
/// axis needs A beyond the machine's limits.
pub fn write_gcode(name: &str, moves: &[AxisMove], machine: &Machine, spindle_rpm: f64) -> Result<String> {
    check(moves)?;
    let mut out = String::new();
    out.push_str(&format!("(swarf five-axis pocketing: {})\n", name.replace(['(', ')'], "")));
    out.push_str(&format!("(machine {}: A from {} to {} deg)\n", machine.kinematics, machine.a_min, machine.a_max));
    out.push_str("G21 G90 G94 G17 G40 G49 G54 G64\n");
    if spindle_rpm > 0.0 {
        out.push_str(&format!("S{} M3\n", num(spindle_rpm, 0)));
    }
    let mut c_prev = 0.0;
    let mut feed = None;
    for (k, m) in moves.iter().enumerate() {
        let Some((a, c)) = ac_of_axis(m.axis, c_prev, machine) else {
            return Err(Error::job(
                "five-axis post",
                format!(
                    "move {k}: the axis ({:.4}, {:.4}, {:.4}) needs A beyond the machine's {} to {} deg",
                    m.axis.x, m.axis.y, m.axis.z, machine.a_min, machine.a_max
                ),
            ));
        };
        c_prev = c;
        let mut line = format!(
            "{} X{} Y{} Z{} A{} C{}",
            if m.rapid { "G0" } else { "G1" },
            num(m.tip.x, 4),
            num(m.tip.y, 4),
            num(m.tip.z, 4),
            num(a, 4),
            num(c, 4)
        );
        if !m.rapid && feed != Some(m.feed) {
            line.push_str(&format!(" F{}", num(m.feed, 1)));
            feed = Some(m.feed);
        }
        out.push_str(&line);
        out.push('\n');
    }
    out.push_str("M5\nM2\n");
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn machine() -> Machine {
        Machine {
            x_rot_point: 3.0,
            y_rot_point: -2.0,
            z_rot_point: 1.0,
            y_offset: 4.0,
            tool_offset: 7.0,
            ..Machine::default()
        }
    }

    #[test]
    fn the_kinematics_invert_each_other() {
        let m = machine();
        for &(tip, a, c) in &[
            (DVec3::new(10.0, -5.0, 3.0), 30.0, 45.0),
            (DVec3::new(-40.0, 12.0, 20.0), -75.0, 200.0),
            (DVec3::new(0.0, 0.0, 0.0), 0.0, 0.0),
        ] {
            let j = trt_inverse(tip, a, c, &m);
            assert!((trt_forward(j, a, c, &m) - tip).length() < 1e-9, "{tip} {a} {c}");
        }
        // at A = C = 0 with no offsets the joints are the tip
        let plain = Machine { z_offset: 0.0, ..Machine::default() };
        assert!(
            (trt_inverse(DVec3::new(1.0, 2.0, 3.0), 0.0, 0.0, &plain) - DVec3::new(1.0, 2.0, 3.0)).length() < 1e-12
        );
    }

    #[test]
    fn axes_and_table_angles() {
        let m = Machine::default();
        for &(a, c) in &[(30.0, 45.0), (80.0, -120.0), (5.0, 179.0)] {
            let axis = axis_of_ac(a, c);
            let (ga, gc) = ac_of_axis(axis, c, &m).expect("within the limits");
            assert!((axis_of_ac(ga, gc) - axis).length() < 1e-12, "{a} {c}: {ga} {gc}");
            assert!((gc - c).abs() < 1e-9);
        }
        // C is unwrapped next to the previous C, and the other branch is taken when it is nearer
        let (_, c) = ac_of_axis(axis_of_ac(20.0, -170.0), 175.0, &m).expect("ok");
        assert!((c - 190.0).abs() < 1e-9, "{c}");
        let (a, c) = ac_of_axis(axis_of_ac(20.0, 0.0), 180.0, &m).expect("ok");
        assert!((a + 20.0).abs() < 1e-9 && (c - 180.0).abs() < 1e-9, "{a} {c}");
        // a vertical axis keeps C
        assert_eq!(ac_of_axis(DVec3::Z, 33.0, &m), Some((0.0, 33.0)));
        // beyond the limits on both branches
        let tight = Machine { a_min: 0.0, a_max: 10.0, ..Machine::default() };
        assert_eq!(ac_of_axis(axis_of_ac(45.0, 0.0), 0.0, &tight), None);
    }

    fn path() -> Vec<AxisMove> {
        // a sweep whose axis turns round the vertical: C must run on without a jump
        let mut v = vec![AxisMove { tip: DVec3::new(0.0, 0.0, 30.0), axis: DVec3::Z, rapid: true, feed: 0.0 }];
        for k in 0..=72 {
            let c = k as f64 * 10.0 - 170.0;
            v.push(AxisMove {
                tip: DVec3::new(k as f64, 0.0, 0.0),
                axis: axis_of_ac(25.0, c),
                rapid: false,
                feed: 800.0,
            });
        }
        v
    }

    #[test]
    fn the_programs_are_written_move_for_move() {
        let tool = FiveTool {
            kind: CutterKind::Ball,
            diameter: 6.0,
            corner_radius: 3.0,
            taper_deg: 0.0,
            flute_length: 25.0,
            shank_diameter: 6.0,
            length: 25.0,
            holder: None,
        };
        let moves = path();
        let cl = write_cl("channel", &tool, &moves).expect("written");
        assert_eq!(cl.lines().filter(|l| l.starts_with("GOTO/")).count(), moves.len());
        assert!(cl.starts_with("$$") && cl.contains("MULTAX/ON\nCUTTER/6,3,0,3,0,0,25\nRAPID\nGOTO/0,0,30,0,0,1\n"));
        assert_eq!(cl.matches("FEDRAT/800,MMPM").count(), 1);
        assert!(cl.ends_with("FINI\n"));
        let g = write_gcode("channel", &moves, &Machine::default(), 12000.0).expect("written");
        let motion: Vec<&str> = g.lines().filter(|l| l.starts_with("G0 ") || l.starts_with("G1 ")).collect();
        assert_eq!(motion.len(), moves.len());
        // C runs on across ±180° without a jump
        let cs: Vec<f64> = motion
            .iter()
            .map(|l| l.split_whitespace().find_map(|w| w.strip_prefix('C')).expect("C").parse().expect("number"))
            .collect();
        assert!(cs.windows(2).all(|w| (w[1] - w[0]).abs() <= 10.0 + 1e-6), "{cs:?}");
        assert!(cs.last().copied().unwrap_or(0.0) > 180.0);
        // beyond the machine's A on both branches: refused
        let tight = Machine { a_min: -10.0, a_max: 10.0, ..Machine::default() };
        assert!(write_gcode("channel", &moves, &tight, 0.0).is_err());
        let bad = [AxisMove { tip: DVec3::new(f64::NAN, 0.0, 0.0), axis: DVec3::Z, rapid: true, feed: 0.0 }];
        assert!(write_cl("x", &tool, &bad).is_err());
    }
}
