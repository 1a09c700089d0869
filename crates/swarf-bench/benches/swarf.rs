//! swarf benchmarks (criterion, `cargo bench -p swarf-bench`), all on `examples/cases/pocket_islands.json`
//! (100 × 80 mm pocket, two islands, Ø6 tool):
//!
//! - `engagement/exact`, `engagement/pixel`: engagement samples per second of each method alone.
//!   The material is the state after replaying the first half of the offset program; the queries
//!   are the sample points (position, direction) of the second half, each method on the same
//!   points;
//! - `replay/full`: a whole replay of the offset program (cutting, both engagement methods,
//!   gouge, collision and plunge checks), in samples per second;
//! - `plan/offset`, `plan/zigzag`: the time of each strategy, planning only (`simulate: false`);
//! - `edt/walls`: the distance transform of the part's cells over the planning grid (the
//!   adaptive planner's distance to the walls), in cells per second;
//! - `rough/offset+sim`: a full `rough()` with the simulation for the report;
//! - `toolseq/table1-exhaustive`: paper 3's search costing every candidate sequence of Table 1's
//!   eight tools (`examples/tools/table1.json`) on `examples/3d/bowl_cavity.json` (the
//!   tools' own geometry included, the replay of the chosen programs not). The same run on any
//!   other 3D case:
//!   `swarf plan CASE --tools examples/tools/table1.json --exhaustive` prints its time.

use criterion::{BatchSize, Criterion, Throughput, criterion_group, criterion_main};
use std::hint::black_box;
use std::time::{Duration, Instant};
use swarf::geom::DVec2;
use swarf::job::rough::{RoughOptions, rough};
use swarf::model::Job;
use swarf::sim::sweep::Path;
use swarf::sim::{RasterSim, SampleKind, SimOptions};
use swarf::strategy::Strategy;
use swarf::toolpath::Toolpath;

fn case() -> Job {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples/cases/pocket_islands.json");
    let text = std::fs::read(path).expect("examples/cases/pocket_islands.json");
    swarf::io::case::parse_case(std::path::Path::new(path), &text).expect("case")
}

fn options(strategy: &str, simulate: bool) -> RoughOptions {
    RoughOptions { strategy: Strategy::from_name(strategy).expect("a strategy"), simulate, ..RoughOptions::default() }
}

fn program(job: &Job) -> Toolpath {
    rough(job, &options("offset", false), &mut |_, _| {}).expect("rough").toolpath
}

fn fresh_sim(job: &Job) -> RasterSim {
    let regions = job.regions(job.radius(), 0.0).expect("regions");
    RasterSim::new(job, &regions, &SimOptions::default()).expect("simulator")
}

fn engagement(c: &mut Criterion) {
    let job = case();
    let tp = program(&job);
    // the sample points of the whole program
    let full = fresh_sim(&job).replay(&tp, &mut |_| {});
    let half = tp.moves.len() / 2;
    let mut first = tp.clone();
    first.moves.truncate(half);
    let mut mid = fresh_sim(&job);
    mid.replay(&first, &mut |_| {});
    // the second half's lateral samples, at most 20 000 of them, spread evenly
    let pts: Vec<(DVec2, f64, DVec2)> = {
        let later: Vec<_> =
            full.samples.iter().filter(|s| s.mi as usize >= half && s.kind == SampleKind::Lateral).collect();
        let stride = (later.len() / 20_000).max(1);
        let paths: Vec<Path> = tp.segments().map(|(f, m)| Path::of(f, m)).collect();
        later
            .iter()
            .step_by(stride)
            .map(|s| {
                let p = &paths[s.mi as usize];
                // the direction at the sample: nearest parameter along the move
                let t = nearest_t(p, s.at.truncate());
                (s.at.truncate(), s.at.z, p.dir(t))
            })
            .collect()
    };
    let n = pts.len() as u64;
    let mut g = c.benchmark_group("engagement");
    g.sample_size(20).warm_up_time(Duration::from_secs(1)).measurement_time(Duration::from_secs(5));
    g.throughput(Throughput::Elements(n));
    g.bench_function("exact", |b| {
        b.iter_batched_ref(
            || mid.clone(),
            |sim| {
                let mut acc = 0.0;
                for &(p, z, d) in &pts {
                    acc += sim.engagement_exact(p, z, d, None);
                }
                black_box(acc)
            },
            BatchSize::LargeInput,
        )
    });
    g.bench_function("pixel", |b| {
        b.iter(|| {
            let mut acc = 0.0;
            for &(p, z, d) in &pts {
                acc += mid.engagement_pixel(p, z, d, None);
            }
            black_box(acc)
        })
    });
    g.finish();
    // one timed pass of each, printed plainly
    let t = Instant::now();
    let mut sim = mid.clone();
    let ex: f64 = pts.iter().map(|&(p, z, d)| sim.engagement_exact(p, z, d, None)).sum();
    let te = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let px: f64 = pts.iter().map(|&(p, z, d)| mid.engagement_pixel(p, z, d, None)).sum();
    let tpx = t.elapsed().as_secs_f64();
    eprintln!(
        "engagement: {n} queries; exact {:.0} samples/s (mean {:.1}°), pixel {:.0} samples/s (mean {:.1}°)",
        n as f64 / te,
        ex / n as f64,
        n as f64 / tpx,
        px / n as f64
    );
}

/// Parameter of the point of `p` nearest `q` (lines exactly, arcs by angle).
fn nearest_t(p: &Path, q: DVec2) -> f64 {
    match *p {
        Path::Line { a, b } => {
            let d = (b - a).truncate();
            let l2 = d.length_squared();
            if l2 < 1e-18 { 0.0 } else { ((q - a.truncate()).dot(d) / l2).clamp(0.0, 1.0) }
        }
        Path::Arc(g) => {
            let v = q - g.center;
            let ang = v.y.atan2(v.x);
            let mut da = ang - g.a0;
            let tau = std::f64::consts::TAU;
            if g.sweep > 0.0 {
                da = da.rem_euclid(tau);
            } else {
                da = -(-da).rem_euclid(tau);
            }
            (da / g.sweep).clamp(0.0, 1.0)
        }
    }
}

fn replay(c: &mut Criterion) {
    let job = case();
    let tp = program(&job);
    let sim0 = fresh_sim(&job);
    let n = sim0.clone().replay(&tp, &mut |_| {}).samples.len() as u64;
    let mut g = c.benchmark_group("replay");
    g.sample_size(10).warm_up_time(Duration::from_secs(1)).measurement_time(Duration::from_secs(35));
    g.throughput(Throughput::Elements(n));
    g.bench_function("full", |b| {
        b.iter_batched(
            || sim0.clone(),
            |mut s| black_box(s.replay(&tp, &mut |_| {}).samples.len()),
            BatchSize::LargeInput,
        )
    });
    g.finish();
    eprintln!("replay: {n} samples, {} moves", tp.moves.len());
}

fn plan(c: &mut Criterion) {
    let job = case();
    let mut g = c.benchmark_group("plan");
    g.sample_size(10).warm_up_time(Duration::from_secs(1)).measurement_time(Duration::from_secs(12));
    for s in ["adaptive", "offset", "zigzag"] {
        let opts = options(s, false);
        let out = rough(&job, &opts, &mut |_, _| {}).expect("rough");
        eprintln!("plan/{}: {} moves, compute {:.3} s", s, out.toolpath.moves.len(), out.report.compute_s);
        g.bench_function(s, |b| {
            b.iter(|| black_box(rough(&job, &opts, &mut |_, _| {}).expect("rough").toolpath.moves.len()))
        });
    }
    g.finish();
}

fn edt(c: &mut Criterion) {
    let job = case();
    let sim = fresh_sim(&job);
    let keep = sim.keep_mask();
    let (nx, ny) = (sim.grid.nx, sim.grid.ny);
    let mut g = c.benchmark_group("edt");
    g.sample_size(20).throughput(Throughput::Elements((nx * ny) as u64));
    g.bench_function("walls", |b| b.iter(|| black_box(swarf::sim::edt::distance(&keep, nx, ny).len())));
    g.finish();
    eprintln!("edt: {nx}×{ny} cells");
}

fn full(c: &mut Criterion) {
    let job = case();
    let opts = options("offset", true);
    let out = rough(&job, &opts, &mut |_, _| {}).expect("rough");
    eprintln!(
        "rough/offset+sim: compute {:.3} s, simulate {:.3} s, max TEA {:.1}°, rest {:.5}",
        out.report.compute_s, out.report.simulate_s, out.report.engagement_deg.max, out.report.rest_fraction
    );
    let mut g = c.benchmark_group("rough");
    g.sample_size(10).warm_up_time(Duration::from_secs(1)).measurement_time(Duration::from_secs(40));
    g.bench_function("offset+sim", |b| {
        b.iter(|| black_box(rough(&job, &opts, &mut |_, _| {}).expect("rough").report.gouges))
    });
    g.finish();
}

fn toolseq(c: &mut Criterion) {
    let root = concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples");
    let case = std::path::PathBuf::from(format!("{root}/3d/bowl_cavity.json"));
    let swarf::io::Input::Mesh(job) = swarf::io::load_input(&case, &Default::default()).expect("case") else {
        panic!("a 3D case")
    };
    let db =
        swarf::model::tooldb::ToolDb::read(std::path::Path::new(&format!("{root}/tools/table1.json"))).expect("tools");
    // (the search only: the replay of the chosen programs is not timed)
    let opts = swarf::job::toolseq::SeqOptions { prune: false, simulate: false, ..Default::default() };
    let mut g = c.benchmark_group("toolseq");
    g.sample_size(10).measurement_time(Duration::from_secs(30));
    g.bench_function("table1-exhaustive", |b| {
        b.iter(|| black_box(swarf::job::toolseq::plan(&job, &db, &opts).expect("plan").sequences.len()))
    });
    g.finish();
}

criterion_group!(benches, engagement, replay, plan, edt, full, toolseq);
criterion_main!(benches);
