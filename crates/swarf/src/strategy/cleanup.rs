//! Clean-up passes: where the clearing passes leave material the tool can reach.
//!
//! Contour-parallel levels spaced by the stepover leave cusps where the level curves have
//! corners (on the medial axis, the tips of the offsets); zigzag rows leave scallops between row
//! ends and the wall contour. The region actually swept by the passes is computed exactly (the
//! union of the tool disks along them), subtracted from the reachable material, and what is left
//! gets more level curves of the wall distance at half, quarter, … the stepover, clipped to near
//! the leftovers, until nothing is left (or four refinements).

use super::{LayerGeom, Params, Pass, PassKind};
use crate::geom::{Area, DVec2};
use crate::model::REGION_TOL;

/// Leftovers thinner than twice this (mm) are numerical slivers, not material.
const SLIVER: f64 = 0.02;

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
pub fn passes(g: &LayerGeom, params: &Params, existing: &[Pass]) -> Vec<Pass> {
    let mut out: Vec<Pass> = Vec::new();
    let mut left = leftover(g, existing);
    for refine in 1..=4 {
        if left.is_empty() {
            break;
        }
        let new = level_curves(g, params, &left, g.step / f64::from(1u32 << refine));
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
pub fn passes_for_leftover(g: &LayerGeom, params: &Params, left: &Area) -> Vec<Pass> {
    let left = left.offset(-SLIVER, REGION_TOL).offset(SLIVER, REGION_TOL).intersection(left).without_slivers(0.01);
    if left.is_empty() {
        return Vec::new();
    }
    let mut out = level_curves(g, params, &left, g.step / 4.0);
    // the wall contour itself, last: what is left against the walls
    if !g.keep.is_empty() {
        // (the wall contour is the edge of the centres' region: clip by the leftover's reach
        // only, or the clipper may drop the contour as outside)
        let zone = left.offset(g.r + 0.01, REGION_TOL);
        out.extend(super::offset::level_passes(&g.keep, g.wall_level, &zone, params, true, PassKind::Cleanup));
    }
    out
}

/// Level curves of the wall distance (or of the stock outline without walls) at spacing
/// `step`, clipped to where the tool touches `left`, farthest from the walls first.
fn level_curves(g: &LayerGeom, params: &Params, left: &Area, step: f64) -> Vec<Pass> {
    let zone = left.offset(g.r, REGION_TOL).intersection(&g.centres);
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
            let mut grown = g.keep.offset(g.wall_level, REGION_TOL);
            loop {
                let level = g.wall_level + k as f64 * step;
                grown = grown.simplified(super::offset::GROW_SIMPLIFY).offset(step, REGION_TOL);
                if zone.difference(&grown).without_slivers(1e-6).is_empty() || k > 10_000 {
                    break;
                }
                new.extend(super::offset::ring_passes(&grown, level, &zone, params, true, PassKind::Cleanup));
                k += 1;
            }
        }
    }
    // farthest from the walls first, like the clearing
    new.sort_by(|a, b| b.level.total_cmp(&a.level));
    new
}
