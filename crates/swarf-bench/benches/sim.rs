//! The two simulators side by side (criterion, `cargo bench -p swarf-bench --bench sim`): the raster
//! ([`RasterSim`]) and the distance fields ([`SdfSim`], paper 4 §4) replaying the same adaptive
//! program of `l_pocket` and `round_pocket`, at equal memory.
//!
//! The raster runs at its default cell size; its cells cost 14 bytes each
//! ([`RasterSim::cell_bytes`]). The distance fields store only the tiles the boundary crosses,
//! so at the same spacing they hold far less: the bench picks the finest spacing (the raster's
//! cell size divided by 1, 2, 3, 4, 6, 8, 12 or 16) whose peak memory ([`SdfSim::peak_bytes`]) stays
//! within the raster's bytes, and times that (`sdf-equal-memory`) and the field at the raster's
//! own spacing (`sdf-same-spacing`) against the raster (`raster`). Each replay builds its model,
//! replays the whole program and measures the rest (`swarf::sim::simulate`). Engagement is
//! sampled at the same points by all three.
//!
//! Accuracy, printed before the timings: the removed volume against a raster of a third of the
//! cell size, and the 95th percentile of the lateral engagement outside the bores against the
//! raster's exact engagement (from the cleared geometry, independent of the cells); for the
//! raster, its pixel engagement (paper 1 eq. 4, from the cells) is the figure its cells give.

use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;
use std::time::Duration;
use swarf::job::rough::{RoughOptions, plan};
use swarf::model::{Job, Regions};
use swarf::report::Stats;
use swarf::sim::{RasterSim, Replay, SampleKind, SdfSim, SimEngine, SimOptions, simulate};
use swarf::toolpath::Toolpath;

fn load(name: &str) -> Job {
    let path = format!("{}/../../examples/cases/{name}.json", env!("CARGO_MANIFEST_DIR"));
    swarf::io::load_job(std::path::Path::new(&path), &Default::default()).expect("case")
}

/// p95 of the lateral engagement outside the bores: the engine's own, and the pixel one.
fn p95(rp: &Replay) -> (f64, f64) {
    let lat: Vec<_> = rp.samples.iter().filter(|s| s.kind == SampleKind::Lateral && !s.bore).collect();
    (
        Stats::of(lat.iter().map(|s| s.tea as f64).collect()).p95,
        Stats::of(lat.iter().map(|s| s.tea_pixel as f64).collect()).p95,
    )
}

struct Case {
    name: &'static str,
    job: Job,
    regions: Regions,
    tp: Toolpath,
    raster: SimOptions,
    sdf_equal: SimOptions,
    sdf_same: SimOptions,
}

fn prepare(name: &'static str) -> Case {
    let job = load(name);
    let opts = RoughOptions::default();
    let planned = plan(&job, &opts).expect("plan").expect("a program");
    let (regions, tp) = (planned.regions, planned.toolpath);
    let res = opts.sim.res_for(job.cutting.tool.diameter);
    // the same engagement sample points for every engine
    let raster = SimOptions { sample_step: Some(res / 2.0), ..Default::default() };
    let run = |o: &SimOptions| simulate(&job, &regions, o, &tp, &mut |_| {}).expect("simulate");
    let bytes = RasterSim::new(&job, &regions, &raster).expect("raster").cell_bytes();
    let (ra, _) = run(&raster);
    let (fine, _) = run(&SimOptions { res: Some(res / 3.0), ..raster.clone() });
    let (exact, pixel) = p95(&ra);
    println!("{name}: {} moves, {} samples, raster {:.3} mm cells", tp.moves.len(), ra.samples.len(), res);
    println!(
        "  reference: removed volume {:.1} mm³ (raster at {:.4} mm), p95 engagement {exact:.2}° (exact)",
        fine.removed_volume,
        res / 3.0
    );
    let verr = |v: f64| 100.0 * (v - fine.removed_volume) / fine.removed_volume;
    println!(
        "  raster      {:>7.4} mm  {:>9} B  volume {:+.3} %  p95 pixel {:+.2}°",
        res,
        bytes,
        verr(ra.removed_volume),
        pixel - exact
    );
    let mut sdf_equal = None;
    for div in [1.0, 2.0, 3.0, 4.0, 6.0, 8.0, 12.0, 16.0] {
        let h = res / div;
        let o = SimOptions { res: Some(h), engine: SimEngine::Sdf, ..raster.clone() };
        let mut sim = SdfSim::new(&job, &regions, &o).expect("sdf");
        let rp = sim.replay(&tp, &mut |_| {});
        let peak = sim.peak_bytes();
        println!(
            "  sdf         {:>7.4} mm  {:>9} B  volume {:+.3} %  p95 {:+.2}°  ({} slabs)",
            h,
            peak,
            verr(rp.removed_volume),
            p95(&rp).0 - exact,
            sim.slab_count()
        );
        if peak <= bytes {
            sdf_equal = Some(o);
        } else {
            break;
        }
    }
    let sdf_same = SimOptions { engine: SimEngine::Sdf, ..raster.clone() };
    let sdf_equal = sdf_equal.unwrap_or_else(|| sdf_same.clone());
    println!("  equal memory: sdf at {:.4} mm", sdf_equal.res.unwrap_or(res));
    Case { name, job, regions, tp, raster, sdf_equal, sdf_same }
}

fn engines(c: &mut Criterion) {
    for name in ["l_pocket", "round_pocket"] {
        let k = prepare(name);
        let mut g = c.benchmark_group(format!("sim/{}", k.name));
        g.sample_size(10).warm_up_time(Duration::from_secs(1)).measurement_time(Duration::from_secs(15));
        for (label, o) in [("raster", &k.raster), ("sdf-equal-memory", &k.sdf_equal), ("sdf-same-spacing", &k.sdf_same)]
        {
            g.bench_function(label, |b| {
                b.iter(|| {
                    let (rp, rest) = simulate(&k.job, &k.regions, o, &k.tp, &mut |_| {}).expect("simulate");
                    black_box((rp.removed_volume, rest.area_mm2))
                })
            });
        }
        g.finish();
    }
}

criterion_group!(benches, engines);
criterion_main!(benches);
