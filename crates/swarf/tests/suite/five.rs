//! 5-axis pocketing (paper 2 §2) on random pockets of the two families the case format
//! describes, checked with swarf's own checks ([`swarf::strategy::five::check`]): no gouge of
//! the floor or the walls deeper than 0.01 mm, no shank or holder collision, no rapid into the
//! part, the floor covered outside the wall band, no turn over 5° between cutting moves, and
//! the axis within 1° of the field (a tapered tool: within its turn from the walls).
//!
//! - *Channels*: an S-shaped centreline, a width varying along it, a saddle floor, the top
//!   offset along the floor's normal turned about the channel's direction and across it (the
//!   field leaning up to about 25° from the normal); open at u = 0, open or walled at u = 1.
//! - *Impeller pockets*: the hub a surface of revolution (a quarter ellipse from the axial
//!   inlet to the radial outlet) between two blades that wrap round the axis and lean; open at
//!   the inlet, the outlet rim a wall or open.
//!
//! Tools of the three kinds. Each case is made from one seed, as JSON in the case format and
//! read by swarf's reader, so a failure reproduces from its seed. `SWARF_FIVE_CASES=N` runs
//! seeds 1 to N (4 by default), `SWARF_FIVE_SEEDS=7,11` those seeds; `SWARF_FIVE_DUMP=DIR` writes the cases there, to run them with
//! `swarf five` (and `SWARF_FIVE_DUMP_ONLY=1` only writes them).

use crate::common::Rng;
use serde_json::{Value, json};
use std::f64::consts::PI;
use swarf::geom::DVec3;
use swarf::io::five::parse_five;
use swarf::strategy::five::{FiveOptions, check, plan};

/// Greville abscissae of a clamped uniform cubic knot vector with `n` control points.
fn greville(n: usize) -> (Vec<f64>, Vec<f64>) {
    let inner = n - 3;
    let mut k = vec![0.0; 4];
    k.extend((1..inner).map(|i| i as f64 / inner as f64));
    k.extend([1.0; 4]);
    let g = (0..n).map(|i| (k[i + 1] + k[i + 2] + k[i + 3]) / 3.0).collect();
    (k, g)
}

fn rotate(v: DVec3, axis: DVec3, ang: f64) -> DVec3 {
    let a = axis.normalize();
    v * ang.cos() + a.cross(v) * ang.sin() + a * a.dot(v) * (1.0 - ang.cos())
}

fn net(nu: usize, nv: usize, f: impl Fn(f64, f64) -> DVec3) -> (Value, Vec<Vec<DVec3>>) {
    let (ku, gu) = greville(nu);
    let (kv, gv) = greville(nv);
    let pts: Vec<Vec<DVec3>> = gu.iter().map(|&u| gv.iter().map(|&v| f(u, v)).collect()).collect();
    let cp: Vec<Vec<[f64; 3]>> = pts.iter().map(|r| r.iter().map(|p| p.to_array()).collect()).collect();
    (json!({"degree_u": 3, "degree_v": 3, "knots_u": ku, "knots_v": kv, "control_points": cp}), pts)
}

/// A random tool: (JSON, diameter).
fn tool(rng: &mut Rng) -> (Value, f64, f64, f64) {
    match rng.int(0, 2) {
        0 => {
            let d = rng.range(4.0, 8.0);
            // stepover for a scallop of about 0.7 of 0.02 mm
            let tol = 0.02;
            let s = 2.0 * ((0.5 * d + 0.7 * tol).powi(2) - (0.5 * d).powi(2)).sqrt();
            (
                json!({"type": "ball", "diameter": d, "length": 45.0, "holder_diameter": 20, "holder_length": 30}),
                d,
                s,
                tol,
            )
        }
        1 => {
            let d = rng.range(4.0, 8.0);
            let rc = rng.range(0.3, 1.0);
            let tol: f64 = 0.05;
            let s = 2.0 * (rc * rc - (rc - 0.6 * tol).powi(2)).sqrt();
            (
                json!({"type": "flat", "diameter": d, "corner_radius": rc, "length": 45.0, "holder_diameter": 20, "holder_length": 30}),
                d,
                s,
                tol,
            )
        }
        _ => {
            let d = rng.range(3.0, 5.0);
            let rc: f64 = 0.25;
            let tol: f64 = 0.05;
            let s = 2.0 * (rc * rc - (rc - 0.6 * tol).powi(2)).sqrt();
            (
                json!({"type": "tapered", "diameter": d, "corner_radius": rc, "taper_deg": rng.range(2.0, 5.0), "length": 45.0}),
                d,
                s,
                tol,
            )
        }
    }
}

/// A random channel case.
pub fn channel(seed: u64) -> Value {
    let mut rng = Rng::new(seed);
    let (tool, d, s, tol) = tool(&mut rng);
    let len = rng.range(70.0, 100.0);
    let (w0, w1) = (rng.range(d + 9.0, 25.0 + d), rng.range(d + 9.0, 25.0 + d));
    let bend = rng.range(2.0, 7.0);
    let (sa, sb) = (rng.range(1.0, 8.0), rng.range(0.0, 3.0));
    let (ta, tb) = (rng.range(5.0, 22.0).to_radians(), rng.range(0.0, 8.0).to_radians());
    let h = rng.range(12.0, 22.0);
    let centre = move |u: f64| DVec3::new(len * (u - 0.5), bend * (2.0 * PI * (u - 0.5)).sin(), 0.0);
    let floor = move |u: f64, v: f64| {
        let t = (centre(u + 1e-5) - centre(u - 1e-5)).normalize();
        let n = DVec3::new(-t.y, t.x, 0.0);
        let w = w0 + (w1 - w0) * u;
        centre(u) + n * ((v - 0.5) * w) + DVec3::Z * (sa * (2.0 * u - 1.0).powi(2) - sb * (2.0 * v - 1.0).powi(2))
    };
    let (fj, fp) = net(14, 7, floor);
    let (_, gu) = greville(14);
    let top = |i: usize, j: usize| -> DVec3 {
        let u = gu[i];
        let (p, e) = (fp[i][j], 1e-4);
        let su = fp[(i + 1).min(13)][j] - fp[i.saturating_sub(1)][j];
        let sv = fp[i][(j + 1).min(6)] - fp[i][j.saturating_sub(1)];
        let mut n = su.cross(sv).normalize();
        if n.z < 0.0 {
            n = -n;
        }
        let _ = e;
        let along = DVec3::new(su.x, su.y, 0.0);
        let across = DVec3::Z.cross(along);
        let d = rotate(rotate(n, along, ta * (2.0 * PI * u).sin()), across, tb * (2.0 * u - 1.0));
        p + d * h
    };
    let tp: Vec<Vec<[f64; 3]>> = (0..14).map(|i| (0..7).map(|j| top(i, j).to_array()).collect()).collect();
    let mut tj = fj.clone();
    tj["control_points"] = json!(tp);
    let u1 = if rng.chance(0.3) { "wall" } else { "open" };
    json!({"units": "mm", "kind": "fiveaxis_pocket", "floor": fj, "top": tj,
        "boundaries": {"u0": "open", "u1": u1, "v0": "wall", "v1": "wall"},
        "tool": tool, "orientation": {"rule": "field"}, "stepover": s, "scallop_tol": tol,
        "wall_band_margin": 0.5, "clearance": 5.0, "note": format!("random channel, seed {seed}")})
}

/// A random impeller pocket case.
pub fn impeller(seed: u64) -> Value {
    let mut rng = Rng::new(seed);
    let (tool, d, s, tol) = tool(&mut rng);
    loop {
        let blades = rng.int(6, 10) as f64;
        let (r_in, z_in) = (rng.range(22.0, 30.0), rng.range(30.0, 40.0));
        let (r_out, z_out) = (rng.range(50.0, 65.0), rng.range(0.0, 6.0));
        let wrap = rng.range(15.0, 40.0).to_radians();
        let (l0, l1) = (rng.range(-8.0, 8.0).to_radians(), rng.range(-8.0, 8.0).to_radians());
        let (h0, h1) = (rng.range(14.0, 19.0), rng.range(8.0, 12.0));
        let thick = rng.range(1.5, 2.5);
        let mer = move |m: f64| {
            let f = m * PI / 2.0;
            (r_out - (r_out - r_in) * f.cos(), z_out + (z_in - z_out) * (1.0 - f.sin()))
        };
        let pitch = 2.0 * PI / blades;
        let floor = move |u: f64, v: f64| {
            let (r, z) = mer(u);
            let half = 0.5 * thick / r;
            let th = wrap * u + half + v * (pitch - 2.0 * half);
            DVec3::new(r * th.cos(), r * th.sin(), z)
        };
        // the room at the inlet
        let w_in = (floor(0.0, 1.0) - floor(0.0, 0.0)).length();
        if w_in < d + 8.0 {
            continue;
        }
        let (fj, _) = net(12, 8, floor);
        let (_, gu) = greville(12);
        let (_, gv) = greville(8);
        let top = |u: f64, v: f64| -> DVec3 {
            let p = floor(u, v);
            let (a, b) = (mer((u + 1e-4).min(1.0)), mer((u - 1e-4).max(0.0)));
            let (dr, dz) = (a.0 - b.0, a.1 - b.1);
            let th = p.y.atan2(p.x);
            let er = DVec3::new(th.cos(), th.sin(), 0.0);
            let et = DVec3::new(-th.sin(), th.cos(), 0.0);
            // the meridian's normal, away from the axis and up
            let n = (er * (-dz) + DVec3::Z * dr).normalize();
            let n = if n.z + n.dot(er) < 0.0 { -n } else { n };
            let lean = l0 + (l1 - l0) * u;
            p + (n * lean.cos() + et * lean.sin()) * (h0 + (h1 - h0) * u)
        };
        let tp: Vec<Vec<[f64; 3]>> = gu.iter().map(|&u| gv.iter().map(|&v| top(u, v).to_array()).collect()).collect();
        let mut tj = fj.clone();
        tj["control_points"] = json!(tp);
        let u1 = if rng.chance(0.5) { "wall" } else { "open" };
        return json!({"units": "mm", "kind": "fiveaxis_pocket", "floor": fj, "top": tj,
            "boundaries": {"u0": "open", "u1": u1, "v0": "wall", "v1": "wall"},
            "tool": tool, "orientation": {"rule": "field"}, "stepover": s, "scallop_tol": tol,
            "wall_band_margin": 0.5, "clearance": 5.0, "note": format!("random impeller pocket, seed {seed}")});
    }
}

fn case(seed: u64) -> Value {
    if seed.is_multiple_of(2) { channel(seed) } else { impeller(seed) }
}

#[test]
fn random_pockets_pass_swarf_s_own_checks() {
    let n: u64 = std::env::var("SWARF_FIVE_CASES").ok().and_then(|s| s.parse().ok()).unwrap_or(4);
    let dump = std::env::var("SWARF_FIVE_DUMP").ok();
    let mut bad = Vec::new();
    let seeds: Vec<u64> = match std::env::var("SWARF_FIVE_SEEDS") {
        Ok(list) => list.split(',').filter_map(|x| x.trim().parse().ok()).collect(),
        Err(_) => (1..=n).collect(),
    };
    for seed in seeds {
        let c = case(seed);
        let text = serde_json::to_string_pretty(&c).expect("json");
        if let Some(dir) = &dump {
            std::fs::write(format!("{dir}/five_random_{seed}.json"), &text).expect("write the case");
            if std::env::var_os("SWARF_FIVE_DUMP_ONLY").is_some() {
                continue;
            }
        }
        let job = match parse_five(std::path::Path::new("random.json"), text.as_bytes()) {
            Ok(j) => j,
            Err(e) => {
                bad.push(format!("seed {seed}: not read: {e}"));
                continue;
            }
        };
        let t = std::time::Instant::now();
        let p = match plan(&job, &FiveOptions::default()) {
            Ok(p) => p,
            Err(e) => {
                bad.push(format!("seed {seed}: not planned: {e}"));
                continue;
            }
        };
        let planned = t.elapsed().as_secs_f64();
        let r = check(&job, &p.moves);
        eprintln!("seed {seed}: planned in {planned:.1} s, checked in {:.1} s", t.elapsed().as_secs_f64() - planned);
        let fails = r.failures();
        if !fails.is_empty() {
            bad.push(format!("seed {seed} ({}): {}; {r:?}", c["note"], fails.join(", ")));
        }
    }
    assert!(bad.is_empty(), "{}", bad.join("\n"));
}
