//! The limits every job is held within, stated once.
//!
//! A CAM engine meets files nobody checked: a drawing in the wrong unit, a coordinate of
//! `1e300`, a step-down of `1e-9`. Each number is checked where it is used, after unit scaling
//! and placement and before any geometry is built, against these limits, and a value outside
//! them is refused with the value and the limit (exit 2 on the command line). They keep every
//! job inside the geometry kernel's range (`i_overlay` maps coordinates onto 32-bit integers
//! over the job's bounds: ±100 m leaves steps of 0.05 µm), inside a memory and work budget (the
//! levels, the estimated cutting length), and every word a post writes a number a controller
//! reads.

/// The largest coordinate of anything in a job (stock, part, fixtures, floor, heights,
/// clearance), mm: ±100 m, beyond the travel of any machine.
pub const MAX_COORD_MM: f64 = 1.0e5;

/// The largest magnitude of any number read from an input file, before its unit: beyond it a
/// value is refused where it is read, with its place, whatever it stands for.
pub const MAX_NUMBER: f64 = 1.0e9;

/// The smallest tool diameter, mm (the smallest end mills sold are 0.1 mm).
pub const MIN_TOOL_MM: f64 = 0.05;

/// The largest tool diameter, mm.
pub const MAX_TOOL_MM: f64 = 1000.0;

/// The highest feed, rapid rate or spindle speed, mm/min or rpm.
pub const MAX_RATE: f64 = 1.0e6;

/// The most levels one job is cut in.
pub const MAX_LEVELS: usize = 500;

/// The most cutting one job may need, mm, estimated as the material's area over the stepover
/// at every level: 20 km, more than 300 hours at 1000 mm/min. Beyond it a job would take hours
/// to plan and gigabytes to hold.
pub const MAX_CUT_MM: f64 = 2.0e7;

/// The most contours a drawing may hold.
pub const MAX_CONTOURS: usize = 10_000;

/// The most level sets a picture of a shape draws.
pub const MAX_SHAPE_LEVELS: usize = 1000;

/// True for a coordinate within [`MAX_COORD_MM`].
pub fn coord_ok(v: f64) -> bool {
    v.is_finite() && v.abs() <= MAX_COORD_MM
}

/// Why a box from `lo` to `hi` (2D or 3D) is refused, if any coordinate of it lies beyond
/// [`MAX_COORD_MM`]: `it reaches from (…) to (…) mm: every coordinate must be within ±… mm`.
pub fn reach_refusal(lo: &[f64], hi: &[f64]) -> Option<String> {
    if lo.iter().chain(hi).copied().all(coord_ok) {
        return None;
    }
    let point = |p: &[f64]| p.iter().map(|v| format!("{v:.6e}")).collect::<Vec<_>>().join(", ");
    Some(format!(
        "it reaches from ({}) to ({}) mm: every coordinate must be within ±{MAX_COORD_MM} mm",
        point(lo),
        point(hi)
    ))
}

/// The number of levels `depth` takes at `stepdown` (at least one), without making them.
pub fn level_count(depth: f64, stepdown: f64) -> f64 {
    ((depth / stepdown) - 1e-9).ceil().max(1.0)
}

/// Why a job of this size is refused, if it is: more than [`MAX_LEVELS`] levels, or more
/// than [`MAX_CUT_MM`] of cutting for `area` mm² at `stepover` mm over `levels` levels.
pub fn work_refusal(levels: f64, area: f64, stepover: f64) -> Option<String> {
    // (NaN fails both: not a number of levels or of millimetres)
    if levels.is_nan() || levels > MAX_LEVELS as f64 {
        return Some(format!("{levels:.0} levels: at most {MAX_LEVELS} (a larger step-down makes fewer)"));
    }
    let cut = area / stepover * levels;
    if cut.is_nan() || cut > MAX_CUT_MM {
        return Some(format!(
            "about {:.0} km of cutting ({area:.0} mm² at a {stepover:.3} mm stepover over {levels:.0} levels): \
             at most {:.0} km (a larger tool, stepover or step-down makes less)",
            cut / 1e6,
            MAX_CUT_MM / 1e6
        ));
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn coordinates_and_work_are_held_within_the_limits() {
        assert!(coord_ok(-MAX_COORD_MM) && !coord_ok(1e300) && !coord_ok(f64::NAN) && !coord_ok(f64::INFINITY));
        assert!(reach_refusal(&[0.0, -5.0], &[MAX_COORD_MM, 5.0]).is_none());
        let why = reach_refusal(&[0.0, 0.0, 0.0], &[2e5, 1.0, f64::NAN]).unwrap();
        assert!(why.contains("to (2.000000e5, 1.000000e0, NaN) mm") && why.contains("±100000 mm"), "{why}");
        assert_eq!(level_count(6.0, 2.0), 3.0);
        assert_eq!(level_count(6.0, 1e-9), 6e9);
        assert!(work_refusal(3.0, 1e4, 1.5).is_none());
        assert!(work_refusal(6e9, 1e4, 1.5).unwrap().contains("levels"));
        assert!(work_refusal(10.0, 1e10, 0.01).unwrap().contains("km of cutting"));
        assert!(work_refusal(f64::NAN, 1.0, 1.0).is_some());
    }
}
