//! The exact search over the prefix tree of the tools (see the module [`super`]): the material
//! each prefix leaves, each tool costed once given each prefix, and the bound that cuts off
//! subtrees.

use super::Sequence;
use super::paths::{Prepared, SLIVER, Z_TOL, boxes_overlap, run_tool};
use crate::geom::Area;
use crate::model::tooldb::ToolRun;
use rayon::prelude::*;
use std::collections::HashMap;

/// The material left by a prefix at every level height, each the one before it minus the last
/// tool's accessible area there (shared by every sequence through the prefix).
#[derive(Default)]
pub(super) struct Materials {
    memo: HashMap<Vec<usize>, std::sync::Arc<Vec<Area>>>,
}

impl Materials {
    pub(super) fn of(&mut self, prep: &Prepared, prefix: &[usize]) -> std::sync::Arc<Vec<Area>> {
        if let Some(m) = self.memo.get(prefix) {
            return m.clone();
        }
        // only the heights of the tools that can follow the prefix are read
        let from = prefix.last().map_or(0, |&j| j + 1);
        let mut wanted = vec![false; prep.zs.len()];
        for t in &prep.tools[from..] {
            for l in &t.levels {
                wanted[l.zi] = true;
            }
        }
        let m: Vec<Area> = match prefix.split_last() {
            None => prep
                .bands
                .par_iter()
                .zip(&wanted)
                .map(|(b, &w)| if w { prep.stock.difference(b).without_slivers(SLIVER) } else { Area::empty() })
                .collect(),
            Some((&j, parent)) => {
                let before = self.of(prep, parent);
                let levels = &prep.tools[j].levels;
                prep.zs
                    .par_iter()
                    .zip(before.par_iter())
                    .zip(&wanted)
                    .map(|((&z, m), &w)| {
                        if !w || m.is_empty() {
                            return Area::empty();
                        }
                        // the tool's highest level at or below z: its levels above cleared less
                        // deep, its levels below nothing above z
                        match levels.iter().find(|l| l.z <= z + Z_TOL) {
                            Some(l) if boxes_overlap(m, &l.access) => m.difference(&l.access).without_slivers(SLIVER),
                            _ => m.clone(),
                        }
                    })
                    .collect()
            }
        };
        let m = std::sync::Arc::new(m);
        self.memo.insert(prefix.to_vec(), m.clone());
        m
    }
}

/// The result of one tool given its prefix.
#[derive(Debug, Clone, Copy)]
pub(super) struct Eval {
    pub(super) run: ToolRun,
    /// Length of path whose disk meets material (a lower bound of the cutting length).
    pub(super) need_mm: f64,
}

pub(super) struct Search<'a> {
    pub(super) prep: &'a Prepared,
    pub(super) memo: HashMap<(usize, Vec<usize>), Eval>,
    pub(super) mats: Materials,
    pub(super) done: Vec<Sequence>,
    pub(super) best: f64,
}

impl Search<'_> {
    pub(super) fn eval(&mut self, k: usize, prefix: &[usize]) -> Eval {
        if let Some(e) = self.memo.get(&(k, prefix.to_vec())) {
            return *e;
        }
        let mats = self.mats.of(self.prep, prefix);
        let (_, run, need_mm) = run_tool(self.prep, k, prefix, &mats);
        let e = Eval { run, need_mm };
        self.memo.insert((k, prefix.to_vec()), e);
        e
    }

    /// Visits the node `prefix` (with its tools' runs): costs the sequence that ends it with the
    /// last tool, then each child.
    pub(super) fn walk(&mut self, prefix: &mut Vec<usize>, runs: &mut Vec<ToolRun>, bound: Option<&ToolRun>) {
        let n = self.prep.tools.len();
        let last = n - 1;
        let m = self.prep.machine.clone();
        let e = self.eval(last, prefix);
        let mut all = runs.clone();
        all.push(e.run);
        let cost = m.cost(&all);
        self.best = self.best.min(cost.total_cost);
        let mut index: Vec<usize> = prefix.clone();
        index.push(last);
        self.done.push(Sequence {
            tools: index.iter().map(|&k| self.prep.tools[k].spec.id.clone()).collect(),
            diameters: index.iter().map(|&k| self.prep.tools[k].spec.diameter).collect(),
            runs: all,
            cost,
            index,
        });
        let from = prefix.last().map_or(0, |&k| k + 1);
        for j in from..last {
            let e = self.eval(j, prefix);
            runs.push(e.run);
            let prune = bound.is_some_and(|b| {
                let mut lb = runs.clone();
                lb.push(*b);
                m.cost(&lb).total_cost > self.best * (1.0 + 1e-12)
            });
            if !prune {
                prefix.push(j);
                self.walk(prefix, runs, bound);
                prefix.pop();
            }
            runs.pop();
        }
    }
}
