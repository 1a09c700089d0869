//! The level driver every strategy uses: one linker (one material model) for the whole program,
//! the levels top down, each announced in the program and started with the tool up, then the
//! finishing contours, then the retract.
//!
//! A strategy says what it cuts at one level ([`Levels::level`]); everything else — where the
//! program starts, the notes, the state of the tool between levels, the finishing passes — is
//! here, once.

use super::LinkOptions;
use super::linker::Linker;
use super::pass::Pass;
use crate::error::Result;
use crate::geom::DVec2;
use crate::model::{Job, Regions};
use crate::sim::SimOptions;
use crate::toolpath::Toolpath;

/// What a strategy cuts, level by level, through the linker.
pub(crate) trait Levels<'a> {
    /// Where the tool starts above: a guess of where the first pass begins (the program starts
    /// where it really does, see [`Linker::finish`]).
    fn first(&self) -> DVec2;
    /// Prepares what depends on the linker's material model, before the first level.
    fn begin(&mut self, _l: &mut Linker<'a>) -> Result<()> {
        Ok(())
    }
    /// Cuts one level at `z`: the tool is up when it is called.
    fn level(&mut self, l: &mut Linker<'a>, z: f64) -> Result<()>;
}

/// The program of `levels` at each of `zs` (top down), then the finishing passes of each level
/// (`finish[i] = (z, passes)`).
#[allow(clippy::too_many_arguments)]
pub(crate) fn drive<'a>(
    job: &'a Job,
    regions: &Regions,
    link: &'a LinkOptions,
    sim: &SimOptions,
    zs: &[f64],
    finish: &[(f64, Vec<Pass>)],
    levels: &mut dyn Levels<'a>,
) -> Result<Toolpath> {
    let mut l = Linker::new(job, regions, link, sim, levels.first())?;
    levels.begin(&mut l)?;
    let n = zs.len();
    for (i, &z) in zs.iter().enumerate() {
        l.tp.note(format!("level {} of {}: z {:.3}", i + 1, n, z));
        l.down_at = None;
        levels.level(&mut l, z)?;
    }
    l.finishing(finish);
    Ok(l.finish())
}

/// Passes that are the same at every level (offset, zigzag): cut in their order, clean-up
/// passes of a level nearest first.
pub(crate) struct SamePasses<'p> {
    /// The passes of one level.
    pub passes: &'p [Pass],
}

impl<'a> Levels<'a> for SamePasses<'_> {
    fn first(&self) -> DVec2 {
        self.passes.first().and_then(|p| p.pts.first().copied()).unwrap_or(DVec2::ZERO)
    }

    fn level(&mut self, l: &mut Linker<'a>, z: f64) -> Result<()> {
        for p in super::linker::order(self.passes, l.tp.end().truncate()) {
            l.pass(p, z);
        }
        Ok(())
    }
}
