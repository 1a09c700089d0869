//! Drawings (DXF, SVG) into jobs: what the drawing's author meant to cut.
//!
//! Roles from layer or group names (`STOCK`, `PART`, `FIXTURE`) win: with a `STOCK` layer the
//! stock is drawn; with a `PART` layer and no stock, the stock is the part's bounding box grown
//! by one tool diameter (clearing round the part). Without roles the contours are read by their
//! nesting, the way a drawing of parts is meant ([`Cut::Auto`]):
//!
//! ```text
//!   plate with holes                 shapes without holes        a rectangle round everything
//!   ┌──────────────┐                 ┌──┐   ╭──╮                 ┌──────────────────┐
//!   │ ○   ┌──┐  ○  │  → a part:      │  │   │  │  → pockets:     │  ╭─╮  ┌─────┐    │ → the stock's
//!   │     └──┘     │    holes        └──┘   ╰──╯    each one     │  ╰─╯  │ ○   │    │   edge: what it
//!   └──────────────┘    cleared,                     cleared      │       └─────┘    │   holds is cut
//!                       outside cut                               └──────────────────┘   as holes
//! ```
//!
//! - when some outermost contour holds another, the outermost contours are *parts* (plates,
//!   brackets, outlined letters): material lies at even nesting depths (outline, island in a
//!   hole, …), their holes are pockets to clear and the outside of each part is cleared to a
//!   stock one tool diameter round the drawing ([`Cut::All`]);
//! - when no contour holds another, each contour is a *pocket* to clear ([`Cut::Pockets`]);
//! - when a single axis-aligned rectangle holds everything else, it is taken as the stock's
//!   edge (a background or the blank's outline): nothing outside it is cut, and what it holds is
//!   cleared as its holes ([`Cut::Holes`]).
//!
//! The user may say otherwise ([`super::Overrides::cut`]): `All`, `Outside` (the parts cut out,
//! their holes left), `Holes` (the holes cleared, the outlines left) or `Pockets` (every
//! outermost contour a pocket wall, nested contours alternately island and pocket: engraved
//! text, for instance). What was read and inferred goes into the [`super::Reading`].

use super::{Overrides, Reading};
use crate::error::{Error, Result, Setting};
use crate::geom::area::Fill;
use crate::geom::{Area, DVec2};
use crate::limits;
use crate::model::{Job, Tool};
use swarf_import::{Drawing, Role};

/// Chord tolerance for flattening the drawing's arcs into region polygons (mm).
pub const FLATTEN_TOL: f64 = 0.001;

/// What of a drawing without role layers is cut.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Cut {
    /// Decided by the drawing's nesting (see the module's documentation).
    #[default]
    Auto,
    /// The outermost contours are parts: their holes cleared and the outside cut to the stock.
    All,
    /// The outermost contours are parts, cut out: only the outside cleared.
    Outside,
    /// The outermost contours are parts: only their holes cleared.
    Holes,
    /// The outermost contours are pocket walls, nested ones alternately islands and pockets.
    Pockets,
}

impl Cut {
    /// The names `--cut` takes, in the order of the variants.
    pub const NAMES: [&'static str; 5] = ["auto", "all", "outside", "holes", "pockets"];

    /// The choice a name stands for.
    pub fn parse(s: &str) -> Option<Cut> {
        Some(match s.trim().to_ascii_lowercase().as_str() {
            "auto" => Cut::Auto,
            "all" => Cut::All,
            "outside" => Cut::Outside,
            "holes" => Cut::Holes,
            "pockets" => Cut::Pockets,
            _ => return None,
        })
    }

    /// The name of the choice.
    pub fn name(self) -> &'static str {
        Cut::NAMES[self as usize]
    }
}

fn ring_of(s: &swarf_import::Shape, scale: f64) -> Vec<DVec2> {
    s.contour.flatten(FLATTEN_TOL).into_iter().map(|p| DVec2::new(p[0], p[1]) * scale).collect()
}

fn area_of(d: &Drawing, scale: f64, pick: impl Fn(Role) -> bool) -> Area {
    let rings: Vec<Vec<DVec2>> = d.shapes.iter().filter(|s| pick(s.role)).map(|s| ring_of(s, scale)).collect();
    Area::from_rings(&rings, Fill::EvenOdd)
}

/// Whether `p` is inside the ring (crossing number; a point on the boundary may go either way).
fn ring_contains(ring: &[DVec2], p: DVec2) -> bool {
    let mut inside = false;
    let mut j = ring.len().wrapping_sub(1);
    for (i, a) in ring.iter().enumerate() {
        let b = ring[j];
        if (a.y > p.y) != (b.y > p.y) && p.x < a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x) {
            inside = !inside;
        }
        j = i;
    }
    inside
}

fn bounds_of(ring: &[DVec2]) -> (DVec2, DVec2) {
    ring.iter()
        .fold((DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)), |(lo, hi), p| (lo.min(*p), hi.max(*p)))
}

/// The nesting depth of each ring: how many of the others hold it (tested at a vertex, against
/// the larger rings whose bounds hold its bounds).
fn depths(rings: &[Vec<DVec2>]) -> Vec<usize> {
    let boxes: Vec<(DVec2, DVec2)> = rings.iter().map(|r| bounds_of(r)).collect();
    let areas: Vec<f64> = rings.iter().map(|r| crate::geom::ring_area(r).abs()).collect();
    (0..rings.len())
        .map(|i| {
            let (lo, hi) = boxes[i];
            let p = rings[i][0];
            (0..rings.len())
                .filter(|&j| {
                    j != i
                        && areas[j] > areas[i]
                        && boxes[j].0.cmple(lo).all()
                        && boxes[j].1.cmpge(hi).all()
                        && ring_contains(&rings[j], p)
                })
                .count()
        })
        .collect()
}

/// Whether the ring is an axis-aligned rectangle (its area that of its bounding box).
fn is_rectangle(ring: &[DVec2]) -> bool {
    let (lo, hi) = bounds_of(ring);
    let boxed = (hi.x - lo.x) * (hi.y - lo.y);
    boxed > 0.0 && (crate::geom::ring_area(ring).abs() - boxed).abs() <= 1e-6 * boxed
}

/// Builds a job from a drawing and the user's options: [`Overrides::DEFAULT_DEPTH`] deep with the
/// default cutting data ([`crate::model::Cutting::DEFAULT`]) unless they say otherwise (the
/// overrides of the cutting data are applied by [`super::load_input`]; the tool diameter is read
/// here too, for the margin of the stock round a part). The drawing is scaled by the
/// placement's scale ([`Overrides::placement`]) and read as the module's documentation says.
pub fn job_from_drawing(d: &Drawing, ov: &Overrides) -> Result<Job> {
    job_and_reading(d, ov).map(|(job, _)| job)
}

/// Refuses, before any geometry is built, a drawing with more than [`limits::MAX_CONTOURS`]
/// contours or one whose points or arcs, scaled by `scale`, reach beyond
/// [`limits::MAX_COORD_MM`].
fn check_size(d: &Drawing, scale: f64) -> Result<()> {
    if d.shapes.len() > limits::MAX_CONTOURS {
        return Err(Error::input(
            &d.path,
            "drawing",
            format!("{} closed contours: at most {}", d.shapes.len(), limits::MAX_CONTOURS),
        ));
    }
    for s in &d.shapes {
        let far = s.contour.vertices.iter().find(|v| !(limits::coord_ok(v.x * scale) && limits::coord_ok(v.y * scale)));
        if let Some(v) = far {
            return Err(Error::input(
                &d.path,
                &s.origin,
                format!(
                    "a point at ({:e}, {:e}) mm: every coordinate must be within ±{} mm (is the unit right?)",
                    v.x * scale,
                    v.y * scale,
                    limits::MAX_COORD_MM
                ),
            ));
        }
        for seg in s.contour.segments() {
            if let swarf_import::contour::Segment::Arc { radius, .. } = seg
                && !limits::coord_ok(radius * scale)
            {
                return Err(Error::input(
                    &d.path,
                    &s.origin,
                    format!("an arc of radius {:e} mm: at most {} mm", radius * scale, limits::MAX_COORD_MM),
                ));
            }
        }
    }
    Ok(())
}

/// [`job_from_drawing`], and what was read and inferred.
pub fn job_and_reading(d: &Drawing, ov: &Overrides) -> Result<(Job, Reading)> {
    let file = &d.path;
    if d.shapes.is_empty() {
        return Err(Error::input(file, "drawing", "no closed contour in the drawing"));
    }
    let scale = ov.placement.scale;
    check_size(d, scale)?;
    let mut reading = Reading { contours: d.shapes.len(), ..Reading::default() };
    let has = |r: Role| d.shapes.iter().any(|s| s.role == r);
    let fixtures = area_of(d, scale, |r| r == Role::Fixture);
    let tool_d = ov.tool_diameter.unwrap_or(Tool::DEFAULT.diameter);
    let roles = has(Role::Stock) || has(Role::Part);
    if roles && ov.cut != Cut::Auto {
        reading
            .warnings
            .push(format!("--cut {} is not used: the drawing's STOCK or PART layer says what to cut", ov.cut.name()));
    }
    let (stock, part) = if has(Role::Stock) {
        reading.inferred.push("the stock and part as their layers say".into());
        (area_of(d, scale, |r| r == Role::Stock), area_of(d, scale, |r| r == Role::Part || r == Role::Auto))
    } else if has(Role::Part) {
        reading.inferred.push("the part as its layer says, cleared round".into());
        let part = area_of(d, scale, |r| r == Role::Part || r == Role::Auto);
        let (lo, hi) = part.bounds().ok_or_else(|| Error::input(file, "PART layer", "the part has no area"))?;
        let m = tool_d.max(1.0);
        (Area::rect(lo.x - m, lo.y - m, hi.x + m, hi.y + m), part)
    } else {
        by_nesting(d, ov, scale, tool_d, &mut reading)?
    };
    if stock.is_empty() {
        return Err(Error::input(file, "STOCK layer", "the stock contours enclose no area"));
    }
    let depth = ov.depth.unwrap_or(Overrides::DEFAULT_DEPTH);
    if !(depth.is_finite() && depth > 0.0) {
        return Err(Error::setting(Setting::Depth, format!("{depth} mm: the depth must be positive")));
    }
    let drawn: Vec<DVec2> = d.shapes.iter().flat_map(|s| ring_of(s, scale)).collect();
    if !drawn.is_empty() {
        let (lo, hi) = bounds_of(&drawn);
        reading.size_mm = [hi.x - lo.x, hi.y - lo.y, depth];
    }
    let name = file.file_stem().and_then(|s| s.to_str()).unwrap_or("drawing").to_string();
    Ok((Job { fixtures, ..Job::new(name, stock, part, tool_d, depth) }, reading))
}

/// Stock and part of a drawing without roles, read by nesting (the module's rules).
fn by_nesting(d: &Drawing, ov: &Overrides, scale: f64, tool_d: f64, reading: &mut Reading) -> Result<(Area, Area)> {
    let file = &d.path;
    let rings: Vec<Vec<DVec2>> =
        d.shapes.iter().filter(|s| s.role == Role::Auto).map(|s| ring_of(s, scale)).filter(|r| r.len() >= 3).collect();
    if rings.is_empty() {
        return Err(Error::input(file, "drawing", "the contours enclose no area"));
    }
    let depth = depths(&rings);
    let tops: Vec<usize> = (0..rings.len()).filter(|&i| depth[i] == 0).collect();
    let nested = depth.iter().any(|&k| k > 0);
    let background = tops.len() == 1 && nested && is_rectangle(&rings[tops[0]]);
    let cut = match ov.cut {
        Cut::Auto if background => Cut::Holes,
        Cut::Auto if nested => Cut::All,
        Cut::Auto => Cut::Pockets,
        c => c,
    };
    let count = |pred: &dyn Fn(usize) -> bool| depth.iter().filter(|&&k| pred(k)).count();
    let (lo, hi) = bounds_of(&rings.iter().flatten().copied().collect::<Vec<_>>());
    let why = if ov.cut != Cut::Auto {
        "as asked".to_string()
    } else if background {
        let (a, b) = bounds_of(&rings[tops[0]]);
        format!(
            "the {:.1} × {:.1} mm rectangle round everything taken as the stock's edge (--cut all cuts round it too)",
            b.x - a.x,
            b.y - a.y
        )
    } else if nested {
        "outlines that hold holes read as parts (--cut pockets reads them as pocket walls)".to_string()
    } else {
        "no contour holds another: each one a pocket (--cut outside cuts round them instead)".to_string()
    };
    reading.cut = Some(cut);
    let even_odd = Area::from_rings(&rings, Fill::EvenOdd);
    if cut == Cut::Pockets {
        reading.pockets = count(&|k| k % 2 == 0);
        reading.islands = count(&|k| k % 2 == 1);
        reading.inferred.push(format!("pockets: {why}"));
        let m = 2.0 * tool_d.max(1.0) + 5.0;
        let frame = Area::rect(lo.x - m, lo.y - m, hi.x + m, hi.y + m).difference(&even_odd);
        return Ok((even_odd, frame));
    }
    reading.parts = if background { 0 } else { tops.len() };
    reading.pockets = count(&|k| k % 2 == 1);
    reading.islands = count(&|k| k >= 2 && k % 2 == 0);
    let outlines: Vec<Vec<DVec2>> = tops.iter().map(|&i| rings[i].clone()).collect();
    let filled = Area::from_rings(&outlines, Fill::NonZero);
    let m = tool_d.max(1.0);
    let around = Area::rect(lo.x - m, lo.y - m, hi.x + m, hi.y + m);
    let what = match cut {
        Cut::All => "holes and outside cut",
        Cut::Outside => "cut out round the outside, holes left",
        _ => "holes cleared",
    };
    reading.inferred.push(format!("{what}: {why}"));
    Ok(match cut {
        Cut::All => (around, even_odd),
        Cut::Outside => (around, filled),
        _ => {
            let holes = filled.difference(&even_odd);
            if holes.is_empty() {
                return Err(Error::input(
                    file,
                    "drawing",
                    "nothing to cut: no outline holds a hole (--cut pockets clears inside the outlines, --cut outside round them)",
                ));
            }
            let big = 2.0 * tool_d.max(1.0) + 5.0;
            let frame = Area::rect(lo.x - big, lo.y - big, hi.x + big, hi.y + big).difference(&holes);
            (holes, frame)
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use swarf_import::{Contour, Drawing, Shape, Units};

    fn shape(c: Contour) -> Shape {
        Shape { contour: c, role: Role::Auto, layer: String::new(), origin: "test".into() }
    }

    fn rect(x0: f64, y0: f64, x1: f64, y1: f64) -> Contour {
        Contour::polygon(&[[x0, y0], [x1, y0], [x1, y1], [x0, y1]])
    }

    fn drawing(cs: Vec<Contour>) -> Drawing {
        Drawing {
            path: "test.dxf".into(),
            units: Units::Millimetre,
            units_from: "test".into(),
            units_assumed: false,
            shapes: cs.into_iter().map(shape).collect(),
            skipped: Vec::new(),
            layers: Vec::new(),
        }
    }

    fn read(d: &Drawing, cut: Cut) -> (Job, Reading) {
        job_and_reading(d, &Overrides { cut, ..Overrides::DEFAULT }).unwrap()
    }

    /// Whether the job clears the material at `p` (in the stock, not the part).
    fn cleared(job: &Job, p: [f64; 2]) -> bool {
        let p = DVec2::new(p[0], p[1]);
        job.stock.contains(p) && !job.part.contains(p)
    }

    /// Whether the part keeps the material at `p`.
    fn kept(job: &Job, p: [f64; 2]) -> bool {
        job.part.contains(DVec2::new(p[0], p[1]))
    }

    /// A bracket: an L-shaped plate (not a rectangle) with two round holes.
    fn bracket() -> Drawing {
        let outline =
            Contour::polygon(&[[0.0, 0.0], [100.0, 0.0], [100.0, 30.0], [30.0, 30.0], [30.0, 80.0], [0.0, 80.0]]);
        drawing(vec![outline, Contour::circle(15.0, 15.0, 6.0), Contour::circle(80.0, 15.0, 6.0)])
    }

    #[test]
    fn a_plate_with_holes_is_cut_out_with_its_holes_cleared() {
        let (job, r) = read(&bracket(), Cut::Auto);
        assert_eq!(r.cut, Some(Cut::All));
        assert_eq!((r.parts, r.pockets, r.islands), (1, 2, 0));
        assert!(cleared(&job, [15.0, 15.0]) && cleared(&job, [80.0, 15.0]), "holes cleared");
        assert!(cleared(&job, [-3.0, 40.0]) && cleared(&job, [60.0, 60.0]), "the outside cut");
        assert!(kept(&job, [50.0, 15.0]) && kept(&job, [15.0, 60.0]), "the plate stays");
        assert!(r.inferred[0].contains("parts"), "{:?}", r.inferred);
    }

    #[test]
    fn the_user_chooses_outside_or_holes_only_or_pockets() {
        let d = bracket();
        let (job, _) = read(&d, Cut::Outside);
        assert!(cleared(&job, [60.0, 60.0]) && !cleared(&job, [15.0, 15.0]) && kept(&job, [15.0, 15.0]));
        let (job, _) = read(&d, Cut::Holes);
        assert!(cleared(&job, [15.0, 15.0]) && !cleared(&job, [60.0, 60.0]) && !cleared(&job, [50.0, 15.0]));
        let (job, r) = read(&d, Cut::Pockets);
        assert_eq!((r.parts, r.pockets, r.islands), (0, 1, 2));
        assert!(cleared(&job, [50.0, 15.0]) && kept(&job, [15.0, 15.0]) && !cleared(&job, [60.0, 60.0]));
    }

    #[test]
    fn a_rectangle_round_everything_is_the_stock_edge_and_its_contents_are_cut() {
        // a pocket with an island inside a drawn blank: the blank is not cut round
        let d = drawing(vec![
            rect(0.0, 0.0, 120.0, 80.0),
            Contour::polygon(&[[20.0, 20.0], [100.0, 20.0], [100.0, 60.0], [60.0, 70.0], [20.0, 60.0]]),
            Contour::circle(60.0, 40.0, 8.0),
        ]);
        let (job, r) = read(&d, Cut::Auto);
        assert_eq!(r.cut, Some(Cut::Holes));
        assert_eq!((r.parts, r.pockets, r.islands), (0, 1, 1));
        assert!(r.inferred[0].contains("rectangle"), "{:?}", r.inferred);
        assert!(cleared(&job, [30.0, 30.0]), "the pocket cleared");
        assert!(!cleared(&job, [60.0, 40.0]) && kept(&job, [60.0, 40.0]), "the island stays");
        assert!(!cleared(&job, [10.0, 10.0]) && !cleared(&job, [-3.0, 40.0]), "nothing cut round the blank");
        // --cut all cuts round the blank too
        let (job, _) = read(&d, Cut::All);
        assert!(cleared(&job, [-3.0, 40.0]) && cleared(&job, [30.0, 30.0]));
    }

    #[test]
    fn shapes_that_hold_nothing_are_pockets() {
        let d = drawing(vec![rect(0.0, 0.0, 30.0, 20.0), Contour::circle(60.0, 10.0, 10.0)]);
        let (job, r) = read(&d, Cut::Auto);
        assert_eq!(r.cut, Some(Cut::Pockets));
        assert_eq!(r.pockets, 2);
        assert!(cleared(&job, [15.0, 10.0]) && cleared(&job, [60.0, 10.0]) && !cleared(&job, [45.0, 10.0]));
        // nothing to cut as holes
        let e = job_and_reading(&d, &Overrides { cut: Cut::Holes, ..Overrides::DEFAULT }).unwrap_err();
        assert!(e.to_string().contains("--cut pockets"), "{e}");
    }

    #[test]
    fn outlined_text_stands_as_islands_or_is_engraved_as_asked() {
        // "OI": an O with its counter, an I without one
        let o = Contour::polygon(&[[0.0, 0.0], [20.0, 0.0], [24.0, 15.0], [20.0, 30.0], [0.0, 30.0], [-4.0, 15.0]]);
        let counter = Contour::polygon(&[[6.0, 8.0], [14.0, 8.0], [14.0, 22.0], [6.0, 22.0]]);
        let i = rect(30.0, 0.0, 38.0, 30.0);
        let d = drawing(vec![o, counter, i]);
        let (job, r) = read(&d, Cut::Auto);
        assert_eq!((r.parts, r.pockets), (2, 1));
        assert!(kept(&job, [2.0, 15.0]) && kept(&job, [34.0, 15.0]), "letters stand");
        assert!(cleared(&job, [10.0, 15.0]) && cleared(&job, [27.0, 15.0]), "counter and round cleared");
        let (job, _) = read(&d, Cut::Pockets);
        assert!(cleared(&job, [2.0, 15.0]) && cleared(&job, [34.0, 15.0]), "letters engraved");
        assert!(!cleared(&job, [10.0, 15.0]) && !cleared(&job, [27.0, 15.0]), "counter and round stay");
    }

    #[test]
    fn role_layers_win_over_the_cut_asked() {
        let mut d = bracket();
        for s in &mut d.shapes {
            s.role = Role::Part;
        }
        let (job, r) = read(&d, Cut::Pockets);
        assert!(cleared(&job, [15.0, 15.0]) && kept(&job, [50.0, 15.0]));
        assert!(r.warnings.iter().any(|w| w.contains("--cut pockets")), "{:?}", r.warnings);
    }

    #[test]
    fn the_scale_applies_to_the_drawing() {
        let ov = Overrides {
            placement: crate::geom::mesh::Placement { scale: 25.4, ..Default::default() },
            ..Overrides::DEFAULT
        };
        let (job, r) = job_and_reading(&bracket(), &ov).unwrap();
        assert!((r.size_mm[0] - 2540.0).abs() < 1e-6);
        assert!(kept(&job, [50.0 * 25.4, 15.0 * 25.4]));
    }

    #[test]
    fn cut_names_round_trip() {
        for name in Cut::NAMES {
            assert_eq!(Cut::parse(name).map(Cut::name), Some(name));
        }
        assert_eq!(Cut::parse("inside"), None);
    }
}
