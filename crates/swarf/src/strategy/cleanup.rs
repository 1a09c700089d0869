//! Clean-up passes: where the clearing passes leave material the tool can reach.
//!
//! Contour-parallel levels spaced by the stepover leave cusps where the level curves have
//! corners (on the medial axis, the tips of the offsets); zigzag rows leave scallops between row
//! ends and the wall contour. The region actually swept by the passes is computed exactly (the
//! union of the tool disks along them), subtracted from the reachable material, and what is left
//! gets more level curves of the wall distance at half, quarter, … the stepover, clipped to near
//! the leftovers, until nothing is left (or four refinements).
//!
//! The adaptive strategy's clean-up ([`passes_for_leftover`]) takes the corners where the walls
//! close round the tool in stages, so that no pass meets the corner's remnant on a whole
//! quarter of its circle: its level curves have fillets of 0.4·R there, then passes along the
//! wall contour near each corner bring the fillet down by 0.7 at a time to the wall contour's
//! own (0.15·R at most), and the wall contour comes last.

use super::AdaptiveOptions;
use crate::geom::area::Fill;
use crate::geom::{Area, DVec2};
use crate::model::REGION_TOL;
use crate::plan::pass::ZONE_TOL;
use crate::plan::{LayerGeom, Pass, PassKind};

/// Leftovers thinner than twice this (mm) are numerical slivers, not material.
const SLIVER: f64 = 0.02;

/// Radius, as a fraction of the tool radius, of the fillets the adaptive clean-up's wall contour
/// puts in the corners its tool centres cannot turn round.
const CORNER_ROUND: f64 = 0.15;

/// Share of the reachable area that the fillets of the wall contour may leave, at most.
const REST_BUDGET: f64 = 0.003;

/// Radius, as a fraction of the tool radius, of the fillets the adaptive clean-up's level
/// curves put in the corners where the walls close round the tool.
///
/// A level curve with a sharp corner there steps into the corner's remnant on the whole
/// quarter of its circle that faces the corner (about 95° at any spacing: the curve before it
/// swept only its own corner disk there). With fillets of 0.4·R, moved a level's spacing `s`
/// along the bisector at a time, the tool meets about the reference engagement of a stepover
/// of 4·s there (a 90° corner, by a fine raster of the cuts: 35°, 52° and 75° at s = 0.05,
/// 0.1 and 0.2·R, whose references are 37°, 53° and 78°).
const CORNER_LEVEL: f64 = 0.4;

/// Ratio of the fillet radii of the corner passes that take the corners from the level
/// curves' fillets ([`CORNER_LEVEL`]) down to the wall contour's: each pass along the wall
/// contour rounded to the next smaller radius meets about 35° of its circle in a 90° corner,
/// whatever the radius (the same raster; the apex advances by (√2 − 1)·0.3·ρ).
const CORNER_RATIO: f64 = 0.7;

/// Most corner passes between the level curves and the wall contour (0.4·R down to 0.015·R).
const CORNER_PASSES: usize = 10;

/// The area the passes sweep, slightly under-estimated (simplified within 5 µm, tool radius
/// less 10 µm): leftovers are then over-estimated by slivers that [`leftover`] drops.
fn swept(passes: &[Pass], r: f64) -> Area {
    let paths: Vec<Vec<DVec2>> = passes
        .iter()
        .map(|p| {
            let mut v = p.pts.clone();
            if p.closed && !v.is_empty() {
                v.push(v[0]);
            }
            crate::geom::simplify::douglas_peucker(&v, 0.005)
        })
        .collect();
    Area::stroke(&paths, r - 0.01, false, 0.005)
}

/// Material the passes leave, without slivers.
pub fn leftover(g: &LayerGeom, passes: &[Pass]) -> Area {
    let left = g.reachable.difference(&swept(passes, g.r));
    left.offset(-SLIVER, REGION_TOL).offset(SLIVER, REGION_TOL).intersection(&left).without_slivers(0.01)
}

/// Extra passes that clear what `existing` leaves.
pub fn passes(g: &LayerGeom, climb: bool, existing: &[Pass]) -> Vec<Pass> {
    let mut out: Vec<Pass> = Vec::new();
    let mut left = leftover(g, existing);
    for refine in 1..=4 {
        if left.is_empty() {
            break;
        }
        let new = level_curves(g, climb, &left, g.step / f64::from(1u32 << refine), 0.0);
        if new.is_empty() {
            break;
        }
        let all: Vec<Pass> = existing.iter().chain(out.iter()).chain(new.iter()).cloned().collect();
        left = leftover(g, &all);
        out.extend(new);
    }
    out
}

/// Passes for a leftover known otherwise (the adaptive strategy reads it off its material
/// model): level curves at a quarter of the stepover near it, in one round.
///
/// `cell` is the size of the raster cells the leftover was read from: the leftover is a
/// staircase with a vertex at every cell corner, and offsets of it by the tool radius (round
/// joins at every vertex) would cost more than the rest of the planning. It is simplified
/// within a cell first, and the zones it gives are grown by as much (they only say where the
/// clean-up passes are clipped).
pub fn passes_for_leftover(g: &LayerGeom, climb: bool, opts: &AdaptiveOptions, left: &Area, cell: f64) -> Vec<Pass> {
    let left = left.offset(-SLIVER, REGION_TOL).offset(SLIVER, REGION_TOL).intersection(left).without_slivers(0.01);
    if left.is_empty() && !opts.full_wall_contour {
        return Vec::new();
    }
    let left = left.simplified(cell);
    let level_rho = if opts.corner_fillets { CORNER_LEVEL * g.r } else { 0.0 };
    let mut out = if left.is_empty() {
        Vec::new()
    } else {
        level_curves(g, climb, &left.offset(cell, ZONE_TOL), g.step / 4.0, level_rho)
    };
    // the wall contour itself, last: what is left against the walls
    if !g.keep.is_empty() {
        // (the wall contour is the edge of the centres' region: clip by the leftover's reach
        // only, or the clipper may drop the contour as outside)
        let zone = if opts.full_wall_contour {
            g.centres_grown(g.r + cell)
        } else {
            std::borrow::Cow::Owned(left.offset(g.r + 0.01 + cell, ZONE_TOL))
        };
        // with the corners where the walls close round the tool rounded off: a tool driven
        // into such a corner meets the material it can never clear on a quarter of its
        // circumference, a 90° engagement however little it removes; the fillet (0.15·R: at a
        // 90° corner it holds the tool 0.06·R off the corner) leaves a sliver of a few tenths
        // of a mm² instead (pocket_islands: the worst corner reads 80° instead of 82° at 0.05·R)
        // the fillets leave a crescent of about (1 / cos(φ/2) − 1)·ρ thick along φ·R of the
        // tool's circle at each corner turning by φ: ρ is kept small enough that all of them
        // together stay under REST_BUDGET of the reachable area (tight pockets have many
        // corners for their size)
        let per_rho: f64 = g
            .walls
            .rings()
            .flat_map(|r| away_turns(r).into_iter())
            .map(|phi| (1.0 / (0.5 * phi).cos().max(0.1) - 1.0) * phi * g.r * 0.5)
            .sum();
        let rho = if opts.corner_fillets {
            (CORNER_ROUND * g.r).min(REST_BUDGET * g.reachable.area() / per_rho.max(1e-12))
        } else {
            0.0
        };
        // from the level curves' fillets down to the wall contour's, in the corners only
        let mut corner = level_rho;
        let mut between = Vec::new();
        while corner > rho * 1.05 && between.len() < CORNER_PASSES && !left.is_empty() {
            between.push(corner);
            corner *= CORNER_RATIO;
        }
        out.extend(corner_passes(g, climb, &between, &zone));
        let rings = round_corners(&g.walls, rho);
        out.extend(super::offset::rings_passes(&rings, g.wall_level, &zone, climb, true, PassKind::Cleanup));
    }
    out
}

/// Passes along the wall contour rounded to each radius of `radii` (largest first) near the
/// corners those fillets round (from [`CORNER_LEAD`]·R before the largest fillet to as far
/// after it), within `zone`.
///
/// Where each radius gives one piece near a corner (or a group of corners closer than that),
/// the pieces, radius after radius, make one pass, each joined to the next by a chord: both
/// ends lie on the walls' contour, so the chord crosses the space the piece before cleared.
/// Where a chord would leave the centres' region or run longer than 3·R, the pieces stay
/// passes of their own. Levels a hair above the wall contour's (larger radii higher) keep them
/// before it and in their order through the linker.
fn corner_passes(g: &LayerGeom, climb: bool, radii: &[f64], zone: &Area) -> Vec<Pass> {
    if radii.is_empty() {
        return Vec::new();
    }
    let level = |j: usize| g.wall_level + 1e-6 * (radii.len() - j) as f64;
    // the largest fillets fill the most: each corner is a piece of their fill
    let first = round_corners(&g.walls, radii[0]);
    let fills = Area::from_rings(&first, Fill::EvenOdd).difference(&g.walls).without_slivers(1e-4);
    let near = fills.offset(CORNER_LEAD * g.r, ZONE_TOL).intersection(zone);
    // (the smaller radii only where a corner stands in the zone: each is a closing of the whole
    // layer's walls, most of a small clean-up's planning)
    if near.is_empty() {
        return Vec::new();
    }
    let rings: Vec<Vec<Vec<DVec2>>> =
        std::iter::once(first).chain(radii[1..].iter().map(|&rj| round_corners(&g.walls, rj))).collect();
    let inside = g.centres_grown(CHORD_TOL);
    let mut out = Vec::new();
    for corner in near.components() {
        let pieces: Vec<Vec<Pass>> = rings
            .iter()
            .enumerate()
            .map(|(j, r)| super::offset::rings_passes(r, level(j), &corner, climb, true, PassKind::Cleanup))
            .filter(|p| !p.is_empty())
            .collect();
        // one piece a radius (or else the linker links them)
        let all: Vec<&Pass> = pieces.iter().flatten().collect();
        let chords_ok = !all.is_empty()
            && pieces.iter().all(|p| p.len() == 1)
            && all.iter().all(|p| !p.closed && p.pts.len() >= 2)
            && all.windows(2).all(|w| {
                let (a, b) = (*w[0].pts.last().unwrap_or(&DVec2::ZERO), w[1].pts[0]);
                a.distance(b) <= 3.0 * g.r && inside.holds_segment(a, b, 1e-9)
            });
        if chords_ok {
            let pts: Vec<DVec2> = all.iter().flat_map(|p| p.pts.iter().copied()).collect();
            out.push(Pass { pts, closed: false, kind: PassKind::Cleanup, level: level(0), reversible: false });
        } else {
            // (pieces of one radius share a level: the linker takes the larger radii first)
            out.extend(pieces.into_iter().flatten());
        }
    }
    out
}

/// Length of the wall contour each corner pass of [`corner_passes`] runs before and after its
/// largest fillet, as a fraction of the tool radius: enough to take the sliver between one
/// fillet's tangent point and the next one's, short enough that the chord back is short.
const CORNER_LEAD: f64 = 0.1;

/// How far a chord of [`corner_passes`] may stray outside the centres' region (its ends lie on
/// that region's edge), mm.
const CHORD_TOL: f64 = 0.002;

/// Level curves of the wall distance (or of the stock outline without walls) at spacing
/// `step`, clipped to where the tool touches `left`, farthest from the walls first.
///
/// `rho` rounds the corners where the walls close round the tool ([`round_corners`]).
fn level_curves(g: &LayerGeom, climb: bool, left: &Area, step: f64, rho: f64) -> Vec<Pass> {
    let zone = left.offset(g.r, ZONE_TOL).intersection(&g.centres);
    let mut new = Vec::new();
    {
        if g.keep.is_empty() {
            let mut k = 1usize;
            loop {
                let a = g.touch.offset(-(k as f64) * step, REGION_TOL);
                if a.is_empty() || k > 10_000 {
                    break;
                }
                for ring in a.rings() {
                    let mut closed = ring.clone();
                    closed.push(ring[0]);
                    for mut p in zone.clip_polyline(&closed) {
                        super::offset::orient_along(&mut p, &closed);
                        new.push(Pass {
                            pts: p,
                            closed: false,
                            kind: PassKind::Cleanup,
                            level: -(k as f64),
                            reversible: false,
                        });
                    }
                }
                k += 1;
            }
        } else {
            let mut k = 1usize;
            let mut grown = g.walls.clone();
            // the fillets are the closing of the grown walls by ρ, and the closing within the
            // zone depends only on the walls within 2ρ of it: closed there alone, a level costs
            // a clip and the closing of a small piece instead of two offsets of the whole layer
            // (boss_with_clamp's planning: 0.50 s with the whole layer closed at every level,
            // 0.20 s so, 0.14 s closed only near a corner as below, 0.13 s with sharp level
            // curves)
            let window = (rho > 0.0).then(|| zone.offset(2.0 * rho + ZONE_TOL, ZONE_TOL));
            // (and only where the grown walls, in the window's box, have a corner that turns
            // away from them or an arc tighter than 2ρ: elsewhere the closing has nothing to
            // fill)
            let bounds = window.as_ref().and_then(|w| w.bounds());
            let concave_near = |a: &Area| {
                bounds.is_some_and(|(lo, hi)| {
                    a.rings().any(|r| {
                        let n = r.len();
                        (0..n).any(|i| {
                            let v = r[i];
                            let inside = v.x >= lo.x && v.y >= lo.y && v.x <= hi.x && v.y <= hi.y;
                            let turn = turn_at(r, i).0;
                            // (the edges each side span about ρ'·turn on an arc of radius ρ')
                            let span = 0.5 * (v.distance(r[(i + n - 1) % n]) + v.distance(r[(i + 1) % n]));
                            inside && (turn > CORNER_MIN || (turn > CONCAVE_MIN && span < 2.0 * rho * turn))
                        })
                    })
                })
            };
            loop {
                let level = g.wall_level + k as f64 * step;
                grown = grown.simplified(super::offset::GROW_SIMPLIFY).offset(step, REGION_TOL);
                if zone.difference(&grown).without_slivers(1e-6).is_empty() || k > 10_000 {
                    break;
                }
                // (at ρ = 0, or where the closing fills next to nothing near the zone, the
                // rings of `grown` as they are, to the bit; where it shuts a channel, `grown`
                // rounded vertex by vertex, as [`round_corners`] would)
                let rings = match &window {
                    Some(w) if concave_near(&grown) => match closing_rings(&grown.intersection(w), rho) {
                        Some((rings, filled)) if filled > FILL_MIN * rho * rho => rings,
                        Some(_) => grown.rings().cloned().collect(),
                        None => fillet_rings(&grown, rho),
                    },
                    _ => grown.rings().cloned().collect(),
                };
                new.extend(super::offset::rings_passes(&rings, level, &zone, climb, true, PassKind::Cleanup));
                k += 1;
            }
        }
    }
    // farthest from the walls first, like the clearing
    new.sort_by(|a, b| b.level.total_cmp(&a.level));
    new
}

/// Smallest turn that [`fillet_away`] rounds, radians.
const FILLET_MIN_TURN: f64 = 5.0 * std::f64::consts::PI / 180.0;

/// The corner of `ring` at vertex `i` when [`fillet_away`] rounds it: how far it turns away
/// from the walls (radians, positive) and the unit directions of the edges in and out.
fn away_turn(ring: &[DVec2], i: usize) -> Option<(f64, DVec2, DVec2)> {
    let (turn, a, b) = turn_at(ring, i);
    (turn > FILLET_MIN_TURN && a != DVec2::ZERO && b != DVec2::ZERO).then_some((turn, a, b))
}

/// How far `ring` (a wall contour: the walls on its left) turns away from the walls at vertex
/// `i` (radians, negative toward them; 0 on a ring of fewer than 3 vertices) and the unit
/// directions of the edges in and out (zero for an edge of no length).
fn turn_at(ring: &[DVec2], i: usize) -> (f64, DVec2, DVec2) {
    let n = ring.len();
    if n < 3 {
        return (0.0, DVec2::ZERO, DVec2::ZERO);
    }
    let (p, q, s) = (ring[(i + n - 1) % n], ring[i], ring[(i + 1) % n]);
    let (a, b) = ((q - p).normalize_or_zero(), (s - q).normalize_or_zero());
    // (a left turn, > 0, is toward the walls)
    (-a.perp_dot(b).atan2(a.dot(b)), a, b)
}

/// Turn away from the walls at a vertex, radians, above which [`level_curves`] closes its grown
/// walls near it whatever the edges' lengths (a single vertex turning by 16° fills
/// [`FILL_MIN`]).
const CORNER_MIN: f64 = 10.0 * std::f64::consts::PI / 180.0;

/// Least turn away from the walls at a vertex, radians, for [`level_curves`] to close its grown
/// walls near it: far below any turn that fills [`FILL_MIN`], and below the turn at each vertex
/// of an arc of radius ρ flattened within 0.001 mm (15° at ρ = 0.12 mm, 4.7° at 1.2 mm), so an
/// arc tighter than ρ, whose vertices each turn little, is closed too (its edges span about
/// ρ·turn each, under the 2ρ·turn that [`level_curves`] asks).
const CONCAVE_MIN: f64 = 0.5 * std::f64::consts::PI / 180.0;

/// The turns away from the walls at the corners of `ring` that [`fillet_away`] rounds.
fn away_turns(ring: &[DVec2]) -> Vec<f64> {
    (0..ring.len()).filter_map(|i| away_turn(ring, i).map(|(phi, _, _)| phi)).collect()
}

/// The wall contours of `walls` with the corners that turn away from the walls rounded to
/// radius `rho`: the morphological closing of the walls (grown by `rho`, shrunk back, united
/// with the walls so that no contour comes closer to them), whose fillets span as many edges as
/// they need (the contour of a wall arc meeting a straight wall is a polygon of short edges, where
/// a fillet within half of each neighbouring edge is a few hundredths of a mm).
///
/// The closing also shuts channels narrower than `2·rho` between walls, where the contour must
/// go; when it fills more than the corners' fillets would (twice their area, rho²·(tan(φ/2) −
/// φ/2) at a turn by φ) or changes the number of contours, each contour is rounded vertex by
/// vertex instead ([`fillet_away`]).
fn round_corners(walls: &Area, rho: f64) -> Vec<Vec<DVec2>> {
    closing_rings(walls, rho).map_or_else(|| fillet_rings(walls, rho), |(rings, _)| rings)
}

/// The wall contours of `walls` rounded vertex by vertex ([`fillet_away`]), where their closing
/// would shut a channel.
fn fillet_rings(walls: &Area, rho: f64) -> Vec<Vec<DVec2>> {
    walls.rings().map(|r| fillet_away(r, rho)).collect()
}

/// Least area, as a fraction of ρ², that the closing in [`level_curves`] must fill near its
/// zone for its rings to be used: a turn by φ fills ρ²·(tan(φ/2) − φ/2), 0.21·ρ² at 90°,
/// 0.0035·ρ² at 25°, under this below about 16°; the closing of boss_with_clamp's layers, which
/// have no such corner near their zones, fills at most 10⁻⁷ mm² by round-off.
const FILL_MIN: f64 = 1e-3;

/// The rings of [`round_corners`]' closing and the area its fillets fill, or `None` where the
/// corners are to be rounded vertex by vertex instead (`rho` not positive, or the closing
/// shuts a channel).
fn closing_rings(walls: &Area, rho: f64) -> Option<(Vec<Vec<DVec2>>, f64)> {
    if rho <= 0.0 || walls.is_empty() {
        return None;
    }
    let closed = walls.union(&walls.offset(rho, CLOSE_TOL).offset(-rho, CLOSE_TOL));
    let fillets: f64 = walls
        .rings()
        .flat_map(|r| away_turns(r).into_iter())
        .map(|phi| rho * rho * ((0.5 * phi).min(1.5).tan() - 0.5 * phi.min(3.0)).max(0.0))
        .sum();
    let filled = closed.area() - walls.area();
    if closed.rings().count() != walls.rings().count() || filled > 2.0 * fillets + rho * CLOSE_TOL * 4.0 {
        return None;
    }
    Some((closed.rings().cloned().collect(), filled))
}

/// Offset tolerance of [`round_corners`]' closing, mm.
const CLOSE_TOL: f64 = 0.002;

/// `ring` (a wall contour: the walls on its left) with every corner that turns away from the
/// walls by more than a few degrees replaced by an arc of radius `rho` (within half of each
/// neighbouring edge). The arc lies on the side away from the walls, so the tool only keeps
/// farther from them.
fn fillet_away(ring: &[DVec2], rho: f64) -> Vec<DVec2> {
    let n = ring.len();
    if n < 3 || rho <= 0.0 {
        return ring.to_vec();
    }
    let mut out = Vec::with_capacity(n + 16);
    for i in 0..n {
        let (p, q, s) = (ring[(i + n - 1) % n], ring[i], ring[(i + 1) % n]);
        let Some((phi, a, b)) = away_turn(ring, i) else {
            out.push(q);
            continue;
        };
        // tangent length of the fillet, within half of each edge
        let t = (rho * (0.5 * phi).tan()).min(0.5 * (q - p).length()).min(0.5 * (s - q).length());
        let rr = t / (0.5 * phi).tan();
        let (t0, t1) = (q - a * t, q + b * t);
        // centre on the right of the travel (away from the walls)
        let c = t0 + DVec2::new(a.y, -a.x) * rr;
        let (a0, a1) = ((t0 - c).y.atan2((t0 - c).x), (t1 - c).y.atan2((t1 - c).x));
        let sweep = crate::geom::wrap_pi(a1 - a0);
        let k = ((sweep.abs() / 5f64.to_radians()).ceil() as usize).max(2);
        for j in 0..=k {
            let ang = a0 + sweep * j as f64 / k as f64;
            out.push(c + DVec2::new(ang.cos(), ang.sin()) * rr);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dist_to_rings(p: DVec2, rings: &[Vec<DVec2>]) -> f64 {
        rings
            .iter()
            .flat_map(|r| (0..r.len()).map(move |i| crate::geom::dist_point_segment(p, r[i], r[(i + 1) % r.len()])))
            .fold(f64::INFINITY, f64::min)
    }

    /// A wall arc (a fine polygon) meeting a straight wall at a right angle: the contour's corner
    /// is rounded to the full radius, although every edge of the arc is far shorter than the
    /// fillet (the vertex-by-vertex fillet is limited to half an edge there).
    #[test]
    fn rounds_a_corner_between_an_arc_and_a_line() {
        let walls = Area::rect(-20.0, -10.0, 20.0, 0.0).union(&Area::disk(DVec2::ZERO, 5.0, 0.001));
        let rho = 1.0;
        let corner = DVec2::new(5.0, 0.0);
        let rounded = round_corners(&walls, rho);
        // the fillet is tangent to the line and the arc: centre ρ above the line, 5 + ρ from
        // the arc's centre
        let centre = DVec2::new(((5.0 + rho) * (5.0 + rho) - rho * rho).sqrt(), rho);
        let d = dist_to_rings(corner, &rounded);
        assert!((d - (corner.distance(centre) - rho)).abs() < 0.01, "corner {d:.3} mm off the contour");
        let by_vertex: Vec<Vec<DVec2>> = walls.rings().map(|r| fillet_away(r, rho)).collect();
        assert!(dist_to_rings(corner, &by_vertex) < 0.1);
        // the contour never comes nearer the walls than the original one
        for r in &rounded {
            for &p in r {
                assert!(!walls.offset(-0.005, 0.001).contains(p), "{p:?} inside the walls");
            }
        }
    }

    /// A channel narrower than 2ρ between two walls: the closing would shut it, so the contours
    /// are rounded vertex by vertex and still run down the channel.
    #[test]
    fn keeps_a_channel_narrower_than_the_fillets() {
        let walls = Area::rect(-20.0, -10.0, 20.0, 10.0).difference(&Area::rect(-20.0, -0.5, 10.0, 0.5));
        let rho = 1.0;
        let rounded = round_corners(&walls, rho);
        assert!(dist_to_rings(DVec2::new(0.0, 0.5), &rounded) < 1e-6);
        assert!(dist_to_rings(DVec2::new(0.0, -0.5), &rounded) < 1e-6);
    }
}
