//! The chosen sequence's programs replayed on the simulator, each on the stock the programs
//! before it left, with what `swarf rough`'s report says of a program.
//!
//! One material model follows the job: each program gets a model of the job for its own tool
//! ([`crate::sim::heights::mesh_model_after`]: the stock box, the part's surface from the mesh,
//! so that a gouge anywhere on it is found) whose stock is what the model of the program before
//! it left. All the models have one cell size (the smallest tool's unless the options set one)
//! and cells aligned to the stock's corner, so the stock passes from one to the next cell for
//! cell.
//!
//! The rest after each program ([`ProgramCheck::rest_volume_mm3`] and the figures beside it) is
//! measured against one reach, the sequence's last and smallest tool's: the least the job can
//! be left with. With one reference for every
//! program the figure only falls, program after program, and what it says after a program is
//! what the tools after it still have to cut; after the last program it is the sequence's final
//! rest, what `swarf rough` reports for the job cut with that tool alone (mostly the steps its
//! levels leave on sloping walls, at most its depth of cut thick).
//!
//! It counts the stock standing more than 0.01 mm above the lowest height that tool reaches
//! without touching the part (the grey closing of the part's heights by its disk), inside the
//! stock box. Engagement is not measured: the exact engagement model starts from the stock box
//! and knows only the cuts of its own tool, so it would read the earlier tools' cuts as
//! material.

use super::Program;
use crate::error::Result;
use crate::model::MeshJob;
use crate::report::Report;
use crate::sim::grid::Grid;
use crate::sim::{Event, HeightMap, SimOptions, heights};
use std::time::Instant;

/// What the simulator found replaying one program on the stock the programs before it left,
/// under the names of `swarf rough`'s report ([`crate::report::Report`]).
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct ProgramCheck {
    /// Moves that gouge the part or go below the floor.
    pub gouges: usize,
    /// Deepest gouge, mm.
    pub gouge_max_mm: f64,
    /// Rapids that touch material.
    pub rapid_collisions: usize,
    /// Deepest a rapid runs into material, mm.
    pub rapid_collision_max_mm: f64,
    /// Steep feed moves down into material (more than 80° from the horizontal).
    pub plunges: usize,
    /// Deepest plunge (its drop), mm.
    pub plunge_max_mm: f64,
    /// Volume the program removed, mm³.
    pub removed_volume_mm3: f64,
    /// Area where the stock stands more than 0.01 mm above the lowest the sequence's last
    /// (smallest) tool reaches, after this program, mm².
    pub rest_area_mm2: f64,
    /// That area over the area the last tool reaches.
    pub rest_fraction: f64,
    /// Volume of that rest material, mm³.
    pub rest_volume_mm3: f64,
    /// Its largest thickness, mm.
    pub rest_max_thickness_mm: f64,
    /// Area the last tool reaches (inside the stock box, below the stock top), mm².
    pub reachable_area_mm2: f64,
    /// Diameter of the tool whose reach the rest is measured against (the last tool's), mm.
    pub rest_reach_diameter_mm: f64,
    /// Where the first gouges are (move index in the program, place, depth); at most 20.
    pub gouge_at: Vec<Event>,
    /// Where the first rapid collisions are; at most 20.
    pub rapid_collision_at: Vec<Event>,
    /// Where the first plunges are; at most 20.
    pub plunge_at: Vec<Event>,
    /// Simulation cell size, mm.
    pub sim_res_mm: f64,
    /// Seconds the replay and the rest took.
    pub simulate_s: f64,
}

/// The simulated stock after each program, over the cells of the stock box.
#[derive(Debug, Clone)]
pub struct RestMaps {
    /// The cells: the stock box's, of the simulation's size.
    pub grid: Grid,
    /// The lowest height the sequence's last tool reaches at each cell (the reference of
    /// [`ProgramCheck`]'s rest), row-major.
    pub low: Vec<f32>,
    /// The stock's top after each program, in order.
    pub after: Vec<Vec<f32>>,
    /// Stock top, mm.
    pub top: f64,
    /// The floor (with its allowance), mm.
    pub bottom: f64,
}

impl RestMaps {
    /// A picture of the stock after program `i` seen from above ([`crate::plot::heights`]): grey
    /// by height (dark is deep), orange where it stands above what the last tool reaches, full
    /// orange from 5 mm thick.
    pub fn png(&self, i: usize) -> Result<Vec<u8>> {
        crate::plot::heights::png(&crate::plot::heights::RestPicture {
            nx: self.grid.nx,
            ny: self.grid.ny,
            stock: self.after.get(i).map_or(&[][..], |a| &a[..]),
            low: &self.low,
            top: self.top,
            bottom: self.bottom,
            tol: 0.05,
            full: 5.0,
            max_side: 600,
        })
    }
}

/// Spacing of the replay's engagement samples, mm: engagement is not reported (see the
/// module's doc), so they are sparse.
const SAMPLE_STEP: f64 = 5.0;

/// Replays `programs` in order on one stock (see the module's doc), fills their checks, and
/// returns the stock after each. `rapid_rate` is the machine's, mm/min.
pub(super) fn replay(job: &MeshJob, programs: &mut [Program], sim: &SimOptions, rapid_rate: f64) -> Result<RestMaps> {
    let smallest = programs.iter().map(|p| p.toolpath.tool.diameter).fold(f64::INFINITY, f64::min);
    let last_r = programs.last().map_or(0.0, |p| p.toolpath.tool.radius());
    let res = sim.res_for(smallest);
    let opts = SimOptions { res: Some(res), sample_step: Some(SAMPLE_STEP), ..sim.clone() };
    let (lo, hi) = (job.stock_lo.truncate(), job.stock_hi.truncate());
    let frame = Grid::covering(lo, hi, 0.0, res, lo);
    let mut maps = RestMaps {
        grid: frame,
        low: Vec::new(),
        after: Vec::new(),
        top: job.stock_hi.z,
        bottom: job.floor + job.allowance_floor,
    };
    let mut stock: Option<HeightMap> = None;
    // the lowest the last tool reaches, on a grid
    let mut reach: Option<(Grid, Vec<f32>)> = None;
    for p in programs.iter_mut() {
        let t0 = Instant::now();
        let tool = &p.toolpath.tool;
        let mut model = heights::mesh_model_after(job, tool, stock.as_ref(), &opts)?;
        // (no engagement: the cuts need not be kept for it)
        model.track_exact = false;
        let rp = model.replay(&p.toolpath, &mut |_| {});
        let low = reach.get_or_insert_with(|| {
            // (once, on the first model's grid: the largest, as its tool is the biggest; every
            // later model's cells are among its cells)
            let low = heights::mesh_reach(job, &model.grid, last_r);
            (model.grid, low)
        });
        let low = low.0.resample(&low.1, &model.grid, f32::INFINITY);
        let rest = heights::rest_above(job, &model, &low, &low, &job.levels());
        let mut rep = Report::default();
        crate::report::fill(&mut rep, &p.toolpath, &rp, &rest, rapid_rate);
        let worst = |v: &[Event]| v.iter().map(|e| e.depth).fold(0.0, f64::max);
        let check = ProgramCheck {
            gouges: rep.gouges,
            gouge_max_mm: rep.gouge_max_mm,
            rapid_collisions: rep.rapid_collisions,
            rapid_collision_max_mm: worst(&rp.rapid_collisions),
            plunges: rep.plunges,
            plunge_max_mm: worst(&rp.plunges),
            removed_volume_mm3: rep.removed_volume_mm3,
            rest_area_mm2: rep.rest_area_mm2,
            rest_fraction: rep.rest_fraction,
            rest_volume_mm3: rep.rest_volume_mm3,
            rest_max_thickness_mm: rep.rest_max_thickness_mm,
            reachable_area_mm2: rep.reachable_area_mm2,
            rest_reach_diameter_mm: 2.0 * last_r,
            gouge_at: rep.gouge_at,
            rapid_collision_at: rep.rapid_collision_at,
            plunge_at: rep.plunge_at,
            sim_res_mm: res,
            simulate_s: t0.elapsed().as_secs_f64(),
        };
        log::debug!(
            "toolseq replay {}: {} gouges, {} rapid collisions, {} plunges, rest {:.0} mm³ ({:.2} s)",
            p.spec.id,
            check.gouges,
            check.rapid_collisions,
            check.plunges,
            check.rest_volume_mm3,
            check.simulate_s
        );
        p.check = Some(check);
        maps.after.push(model.grid.resample(model.heights(), &frame, f32::NEG_INFINITY));
        stock = Some(HeightMap { grid: model.grid, stock: model.heights().to_vec(), part: None });
    }
    if let Some((grid, low)) = &reach {
        maps.low = grid.resample(low, &frame, f32::INFINITY);
    }
    Ok(maps)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::mesh::tests::pocket_block;
    use crate::geom::{DVec2, DVec3};
    use crate::model::tooldb::{ToolRun, ToolSpec};
    use crate::model::{Cutting, Tool};
    use crate::toolpath::{MoveKind, Toolpath};

    /// A program of a flat end mill of diameter `d` that goes down at the pocket's centre by a
    /// rapid to `rapid_to`, then at feed to `z`, and back up.
    fn down_at_centre(d: f64, rapid_to: f64, z: f64) -> Program {
        let spec = ToolSpec {
            id: format!("D{d}"),
            kind: "solid carbide".into(),
            teeth: 2,
            diameter: d,
            width_of_cut: d / 2.0,
            depth_of_cut: 1.0,
            feed_per_tooth: 0.05,
            cutting_speed_m_min: 60.0,
            price: 10.0,
            life_min: 45.0,
        };
        let tool = Tool { diameter: d, number: 1, flutes: 2 };
        let c = DVec2::new(5.0, 5.0);
        let mut tp = Toolpath::new(tool, DVec3::new(c.x, c.y, 13.0), 13.0);
        tp.rapid(DVec3::new(c.x, c.y, rapid_to));
        tp.line(MoveKind::Descend, DVec3::new(c.x, c.y, z), 100.0);
        tp.rapid(DVec3::new(c.x, c.y, 13.0));
        let run = ToolRun { cut_mm: 0.0, air_mm: 0.0, feed_mm_min: 100.0, price: 10.0, life_min: 45.0 };
        Program { spec, number: 1, toolpath: tp, run, check: None }
    }

    #[test]
    fn each_program_is_replayed_on_what_the_ones_before_it_left() {
        // the block [0, 10]² × [0, 10] with a pocket [3, 7]² down to 4, in a stock 2 mm higher
        let job = MeshJob::new(
            "pocket",
            pocket_block(10.0, 4.0),
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(10.0, 10.0, 12.0),
            Cutting { tool: Tool { diameter: 2.0, number: 1, flutes: 2 }, ..Cutting::DEFAULT },
        );
        let sim = SimOptions { res: Some(0.05), ..SimOptions::DEFAULT };
        // the D2 plunges into the pocket down to 6; the D1 then rapids down the hole it left
        // (no collision) and feeds on down to 3.5, half a millimetre through the floor
        let mut programs = vec![down_at_centre(2.0, 12.5, 6.0), down_at_centre(1.0, 6.5, 3.5)];
        let maps = replay(&job, &mut programs, &sim, 5000.0).expect("replayed");
        let (a, b) = (programs[0].check.clone().expect("a check"), programs[1].check.clone().expect("a check"));
        assert_eq!((a.gouges, a.rapid_collisions, a.plunges), (0, 0, 1));
        assert!((a.plunge_max_mm - 6.5).abs() < 1e-9, "{}", a.plunge_max_mm);
        assert_eq!(b.rapid_collisions, 0, "{:?}", b.rapid_collision_at);
        assert_eq!(b.plunges, 1);
        assert!(b.gouges >= 1 && (b.gouge_max_mm - 0.5).abs() < 0.02, "{} gouges, {} mm", b.gouges, b.gouge_max_mm);
        // the rest, against the last tool's reach, only falls; each program removed material
        assert_eq!((a.rest_reach_diameter_mm, b.rest_reach_diameter_mm), (1.0, 1.0));
        assert!(b.rest_volume_mm3 < a.rest_volume_mm3 && a.removed_volume_mm3 > 0.0 && b.removed_volume_mm3 > 0.0);
        assert_eq!(maps.after.len(), 2);
        assert_eq!(maps.low.len(), maps.grid.len());
        // replayed alone, on the stock box, the D1's rapid runs into the pocket's material
        let mut alone = vec![down_at_centre(1.0, 6.5, 3.5)];
        replay(&job, &mut alone, &sim, 5000.0).expect("replayed");
        let c = alone[0].check.as_ref().expect("a check");
        assert_eq!(c.rapid_collisions, 1);
        assert!((c.rapid_collision_max_mm - 5.5).abs() < 1e-9, "{}", c.rapid_collision_max_mm);
    }
}
