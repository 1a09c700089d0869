//! The tool-sequence search (paper 3) on a stepped cavity: a 100 × 80 × 20 mm block with a
//! 60 × 40 mm pocket 10 mm deep and, in its floor, a 12 × 12 mm pocket down to 4 mm that only
//! the smaller tools reach. The part is a height field meshed on a 2 mm grid, so its walls
//! slope over one grid step (a freeform cavity in miniature).
//!
//! Checks: the search (shared work, bound) returns the brute-force optimum, each sequence's
//! cost is what costing it alone gives, every candidate is costed without the bound, and the
//! chosen programs neither plunge nor gouge the part (the tool disk against the mesh's heights,
//! independently of the planner, and the simulator's replay of each).

use swarf::geom::mesh::Mesh;
use swarf::geom::{DVec2, DVec3};
use swarf::job::toolseq::{Decomposition, SeqOptions};
use swarf::model::MeshJob;
use swarf::model::tooldb::{Machine, ToolDb, ToolSpec};
use swarf::model::{Cutting, Width};
use swarf::toolpath::MoveKind;

fn height(x: f64, y: f64) -> f64 {
    if (x - 15.0).abs() < 6.5 && y.abs() < 6.5 {
        4.0
    } else if x.abs() < 30.5 && y.abs() < 20.5 {
        10.0
    } else {
        20.0
    }
}

fn cavity() -> MeshJob {
    let mut tris = Vec::new();
    let s = 2.0;
    let (nx, ny) = (50, 40);
    let p = |i: usize, j: usize| {
        let (x, y) = (-50.0 + i as f64 * s, -40.0 + j as f64 * s);
        DVec3::new(x, y, height(x, y))
    };
    for j in 0..ny {
        for i in 0..nx {
            let (a, b, c, d) = (p(i, j), p(i + 1, j), p(i + 1, j + 1), p(i, j + 1));
            tris.push([a, b, c]);
            tris.push([a, c, d]);
        }
    }
    MeshJob {
        name: "stepped".into(),
        mesh: Mesh { tris, dropped: 0, binary: false },
        stock_lo: DVec3::new(-50.0, -40.0, 0.0),
        stock_hi: DVec3::new(50.0, 40.0, 20.0),
        floor: 0.0,
        allowance: 0.0,
        allowance_floor: 0.0,
        stepdown: 2.0,
        cutting: Cutting::with_tool_diameter(6.0).with_width(Width::Stepover(0.5)),
    }
}

fn tool(id: &str, d: f64, doc: f64, fz: f64, price: f64) -> ToolSpec {
    ToolSpec {
        id: id.into(),
        kind: "solid carbide".into(),
        teeth: 4,
        diameter: d,
        width_of_cut: d / 2.0,
        depth_of_cut: doc,
        feed_per_tooth: fz,
        cutting_speed_m_min: 60.0,
        price,
        life_min: 45.0,
    }
}

fn db() -> ToolDb {
    ToolDb {
        machine: Machine { cost_per_hour: 50.0, rapid_feed_mm_min: 30000.0, tool_change_min: 0.5 },
        // (not sorted: the search sorts by diameter)
        tools: vec![
            tool("T3", 8.0, 2.0, 0.05, 110.0),
            tool("T1", 20.0, 5.0, 0.2, 387.0),
            tool("T4", 6.0, 1.5, 0.03, 90.0),
            tool("T2", 12.0, 3.0, 0.1, 155.0),
        ],
    }
}

#[test]
fn search_finds_the_brute_force_optimum() {
    let job = cavity();
    let db = db();
    let opts = SeqOptions::default();
    let plan = swarf::job::toolseq::plan(&job, &db, &opts).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(plan.candidates, 8);
    // brute force: every subset of the three bigger tools, then the smallest (T4, index 2),
    // each costed on its own
    let bigger = [1usize, 3, 0]; // T1 (20), T2 (12), T3 (8): biggest first
    let mut brute: Vec<(f64, Vec<usize>)> = Vec::new();
    for mask in 0..8u32 {
        let mut seq: Vec<usize> =
            bigger.iter().enumerate().filter(|(b, _)| mask >> b & 1 == 1).map(|(_, &i)| i).collect();
        seq.push(2);
        let c = swarf::job::toolseq::cost_of(&job, &db, &seq, &opts).unwrap_or_else(|e| panic!("{e}"));
        brute.push((c.total_cost, seq));
    }
    brute.sort_by(|a, b| a.0.total_cmp(&b.0));
    let best = plan.best();
    let ids: Vec<String> = brute[0].1.iter().map(|&i| db.tools[i].id.clone()).collect();
    assert_eq!(best.tools, ids, "search {:?} vs brute force {:?}", best.tools, brute);
    assert!(
        (best.cost.total_cost - brute[0].0).abs() <= 1e-9 * brute[0].0,
        "{} vs {}",
        best.cost.total_cost,
        brute[0].0
    );
    // every sequence the search costed costs what it costs alone
    for s in &plan.sequences {
        let ids: Vec<String> = s.tools.clone();
        let (c, _) = brute
            .iter()
            .find(|(_, seq)| seq.iter().map(|&i| db.tools[i].id.clone()).collect::<Vec<_>>() == ids)
            .unwrap_or_else(|| panic!("{ids:?} is not a candidate"));
        assert!((s.cost.total_cost - c).abs() <= 1e-9 * c, "{ids:?}: {} vs {c}", s.cost.total_cost);
    }
    // the sequences differ: the bigger tools pay for themselves or not
    assert!(brute[7].0 > brute[0].0 * 1.05, "{brute:?}");
    // without the bound every candidate is costed, and the best is the same
    let all = swarf::job::toolseq::plan(&job, &db, &SeqOptions { prune: false, ..opts.clone() }).unwrap();
    assert_eq!(all.sequences.len(), 8);
    assert_eq!(all.best().tools, best.tools);
    // Algorithm 3 plans too, and costs every candidate
    let regions =
        swarf::job::toolseq::plan(&job, &db, &SeqOptions { decomposition: Decomposition::Regions, ..opts }).unwrap();
    assert_eq!(regions.sequences.len(), 8);
}

#[test]
fn programs_neither_plunge_nor_gouge() {
    let job = cavity();
    let db = db();
    // a sequence of three tools, so that two of them cut rest material
    let mut small = db.clone();
    small.tools.retain(|t| t.id != "T3");
    let plan = swarf::job::toolseq::plan(&job, &small, &SeqOptions { prune: false, ..Default::default() }).unwrap();
    let seq = plan.sequences.iter().find(|s| s.tools == ["T1", "T2", "T4"]).expect("costed");
    assert!(seq.cost.total_cost > 0.0);
    let res = 0.25;
    let lo = job.stock_lo.truncate();
    let g = swarf::sim::grid::Grid::covering(lo, job.stock_hi.truncate(), 12.0, res, lo);
    let part = swarf::sim::heights::height_map(&job.mesh, &g);
    // the best sequence's programs
    assert_eq!(plan.programs.len(), plan.best().tools.len());
    let mut cut_total = 0.0;
    for p in &plan.programs {
        let tp = &p.toolpath;
        let r = tp.tool.radius();
        let t = tp.totals(30000.0);
        assert_eq!(t.plunges, 0, "{}: plunges", p.spec.id);
        assert!(tp.moves.iter().all(|m| m.kind != MoveKind::Plunge));
        cut_total += t.cut_length_mm;
        // every feed move, sampled every 0.2 mm: the part under the tool disk is not above the
        // tool tip
        for (from, m) in tp.segments() {
            if m.is_rapid() {
                // rapids: above the part and the stock everywhere but where the tool is in air
                // over cleared space: not checked here
                continue;
            }
            let n = ((m.to - from).length() / 0.2).ceil().max(1.0) as usize;
            for k in 0..=n {
                let q = from + (m.to - from) * (k as f64 / n as f64);
                let (Some((i0, j0)), Some((i1, j1))) =
                    (g.cell_of(DVec2::new(q.x - r, q.y - r)), g.cell_of(DVec2::new(q.x + r, q.y + r)))
                else {
                    continue;
                };
                for j in j0..=j1 {
                    for i in i0..=i1 {
                        let c = g.center(i, j);
                        if (c - q.truncate()).length() <= r - res {
                            let h = f64::from(part[j * g.nx + i]);
                            assert!(h <= q.z + 0.02, "{}: gouge at {q:?}: part at {h}", p.spec.id);
                        }
                    }
                }
            }
        }
    }
    assert!(cut_total > 100.0);
    // the simulator's replay of each program, on what the ones before it left, agrees
    for p in &plan.programs {
        let c = p.check.as_ref().expect("replayed");
        assert_eq!((c.gouges, c.rapid_collisions, c.plunges), (0, 0, 0), "{}: {c:?}", p.spec.id);
    }
    // the simulated stock after the last tool: nothing thicker than its depth of cut above the
    // part where the smallest tool reaches (away from the walls by a cell), as the replay says
    let rest = plan.rest.as_ref().expect("replayed");
    let last = plan.programs.last().expect("a program");
    let part: Vec<f32> =
        swarf::sim::heights::height_map(&job.mesh, &rest.grid).into_iter().map(|h| h.max(rest.bottom as f32)).collect();
    let worst = rest_in_reach(rest, &part, last.toolpath.tool.radius());
    assert!(worst <= last.spec.depth_of_cut + 0.1, "rest {worst} mm where the last tool reaches");
    let thick = last.check.as_ref().expect("replayed").rest_max_thickness_mm;
    assert!(thick <= last.spec.depth_of_cut + 0.1, "the replay's rest: {thick} mm");
    // (and the corners no round tool reaches are left: there is rest above the part)
    let after = rest.after.last().expect("a program");
    let max = after.iter().zip(&part).map(|(s, p)| f64::from(s - p)).fold(0.0, f64::max);
    assert!(max > last.spec.depth_of_cut + 1.0, "{max}");
    assert!(rest.png(0).unwrap().starts_with(b"\x89PNG"));
}

/// The thickest stock left above the lowest height a flat tool of radius `r` reaches (the
/// grey closing of the part's heights `part` by its disk, grown by a cell to be fair to the
/// raster), over every third cell of the rest map.
fn rest_in_reach(rest: &swarf::job::toolseq::RestMaps, part: &[f32], r: f64) -> f64 {
    let g = rest.grid;
    let rc = (r / g.res).ceil() as i64 + 1;
    let disk: Vec<(i64, i64)> = (-rc..=rc)
        .flat_map(|dj| (-rc..=rc).map(move |di| (di, dj)))
        .filter(|(di, dj)| ((di * di + dj * dj) as f64).sqrt() * g.res <= r + g.res)
        .collect();
    let at = |v: &[f32], i: i64, j: i64| -> Option<f32> {
        (i >= 0 && j >= 0 && (i as usize) < g.nx && (j as usize) < g.ny).then(|| v[j as usize * g.nx + i as usize])
    };
    // tool tip at each centre: the highest part under the disk
    let tip: Vec<f32> = (0..g.ny as i64)
        .flat_map(|j| (0..g.nx as i64).map(move |i| (i, j)))
        .map(|(i, j)| disk.iter().filter_map(|(di, dj)| at(part, i + di, j + dj)).fold(f32::MIN, f32::max))
        .collect();
    let last = rest.after.last().expect("a tool");
    let mut worst = 0.0f64;
    for j in (0..g.ny as i64).step_by(3) {
        for i in (0..g.nx as i64).step_by(3) {
            let reach = disk.iter().filter_map(|(di, dj)| at(&tip, i + di, j + dj)).fold(f32::MAX, f32::min);
            let k = j as usize * g.nx + i as usize;
            let low = reach.max(part[k]);
            if low >= rest.top as f32 - 0.01 {
                continue;
            }
            worst = worst.max(f64::from(last[k] - low));
        }
    }
    worst
}
