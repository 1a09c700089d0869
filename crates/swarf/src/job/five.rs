//! A 5-axis pocketing job (paper 2 §2): the case read, the path planned
//! ([`crate::strategy::five`]), and written as a CL file and as G-code for the case's machine.

use crate::error::Result;
use crate::model::five::FiveJob;
use crate::post::five::{write_cl, write_gcode};
use crate::strategy::five::{FiveOptions, FivePlan, plan};
use std::time::Instant;

/// A planned and posted 5-axis program.
#[derive(Debug, Clone)]
pub struct FiveProgram {
    /// The plan.
    pub plan: FivePlan,
    /// The CL file.
    pub cl: String,
    /// The G-code for the case's machine.
    pub gcode: String,
    /// Seconds spent planning.
    pub planning_s: f64,
    /// Cutting and rapid length, mm.
    pub length: (f64, f64),
    /// Machining time, minutes: cutting length over the feed and rapid length over the rapid rate.
    pub time_min: f64,
}

/// Plans `job` and posts it.
pub fn run(job: &FiveJob, opts: &FiveOptions) -> Result<FiveProgram> {
    let t = Instant::now();
    let plan = plan(job, opts)?;
    let planning_s = t.elapsed().as_secs_f64();
    let cl = write_cl(&job.name, &job.tool, &plan.moves)?;
    let gcode = write_gcode(&job.name, &plan.moves, &job.machine, 0.0)?;
    let (mut cut, mut rapid) = (0.0, 0.0);
    for w in plan.moves.windows(2) {
        let d = (w[1].tip - w[0].tip).length();
        if w[1].rapid { rapid += d } else { cut += d }
    }
    let time_min = cut / job.feed + rapid / job.rapid_rate;
    Ok(FiveProgram { plan, cl, gcode, planning_s, length: (cut, rapid), time_min })
}

impl FiveProgram {
    /// The picture of the plan as SVG ([`crate::plot::five`]): the shapes in the domain before
    /// and after the variable offset, the path on the floor and the orientation field, titled
    /// with the job's name, the shapes, the cut and the machining time.
    pub fn picture_svg(&self, job: &FiveJob) -> String {
        use crate::plot::five::{FivePicture, svg};
        let tips: Vec<_> = self.plan.moves.iter().map(|m| m.tip).collect();
        let title = format!(
            "{}: {} rounded shapes, {:.0} mm of cut, {:.1} min",
            job.name, self.plan.shapes, self.length.0, self.time_min
        );
        svg(
            job,
            &FivePicture {
                title,
                before: &self.plan.before,
                after: &self.plan.params,
                tips: &tips,
                shape: &self.plan.shape_of,
            },
        )
    }
}
