//! Exact Euclidean distance transform on a grid (Felzenszwalb & Huttenlocher 2012, "Distance
//! transforms of sampled functions"): a pass along the columns (on a binary input, two sweeps)
//! and one along the rows by the lower envelope of parabolas, linear in the number of cells.
//! Written here because the crates that have it (imageproc) bring an image stack with them and
//! work on their own image types; this is sixty lines over a plain slice.

/// Squared distances along one line: `f` holds 0 at sites and `INF` elsewhere (or the squared
/// distances of the previous pass); the result overwrites `d`.
fn pass_1d(f: &[f32], d: &mut [f32], v: &mut [usize], z: &mut [f32]) {
    let n = f.len();
    if n == 0 {
        return;
    }
    let mut k = 0usize;
    v[0] = 0;
    z[0] = f32::NEG_INFINITY;
    z[1] = f32::INFINITY;
    for q in 1..n {
        if f[q] >= INF {
            continue;
        }
        loop {
            let p = v[k];
            if f[p] >= INF {
                // the only parabola so far is an empty site: replace it
                v[k] = q;
                z[k] = f32::NEG_INFINITY;
                z[k + 1] = f32::INFINITY;
                break;
            }
            let s = ((f[q] + (q * q) as f32) - (f[p] + (p * p) as f32)) / (2.0 * q as f32 - 2.0 * p as f32);
            if s <= z[k] && k > 0 {
                k -= 1;
                continue;
            }
            if s <= z[k] {
                v[k] = q;
                z[k] = f32::NEG_INFINITY;
                z[k + 1] = f32::INFINITY;
                break;
            }
            k += 1;
            v[k] = q;
            z[k] = s;
            z[k + 1] = f32::INFINITY;
            break;
        }
    }
    if f[v[0]] >= INF && k == 0 {
        d.iter_mut().for_each(|x| *x = INF);
        return;
    }
    k = 0;
    for (q, dq) in d.iter_mut().enumerate() {
        while z[k + 1] < q as f32 {
            k += 1;
        }
        let p = v[k];
        let dx = q as f32 - p as f32;
        *dq = dx * dx + f[p];
    }
}

/// "Infinitely far" in squared cells.
pub const INF: f32 = 1e20;

/// Distance (in cells) from every cell to the nearest cell where `site` is true, over an
/// `nx × ny` row-major grid; infinite where there is no site at all.
///
/// The first pass (columns) needs no envelope: its input is 0 or ∞, so the squared distance
/// along a column is that to the nearest site above or below, found by one sweep down and one
/// up over the rows, in memory order. The second pass (rows) is the envelope of parabolas,
/// row by row, in parallel on large grids.
pub fn distance(site: &[bool], nx: usize, ny: usize) -> Vec<f32> {
    use rayon::prelude::*;
    if nx == 0 || ny == 0 {
        return Vec::new();
    }
    const NONE: u32 = u32::MAX;
    let sq = |d: u32| if d == NONE { INF } else { d as f32 * d as f32 };
    let mut g = vec![0f32; nx * ny];
    // cells since the last site, per column
    let mut run = vec![NONE; nx];
    for (row, srow) in g.chunks_mut(nx).zip(site.chunks(nx)) {
        for ((c, s), r) in row.iter_mut().zip(srow).zip(run.iter_mut()) {
            *r = if *s { 0 } else { r.saturating_add(1) };
            *c = sq(*r);
        }
    }
    run.fill(NONE);
    for (row, srow) in g.chunks_mut(nx).zip(site.chunks(nx)).rev() {
        for ((c, s), r) in row.iter_mut().zip(srow).zip(run.iter_mut()) {
            *r = if *s { 0 } else { r.saturating_add(1) };
            *c = c.min(sq(*r));
        }
    }
    let scratch = || (vec![0usize; nx + 1], vec![0f32; nx + 2], vec![0f32; nx]);
    let row_pass = |(v, z, out): &mut (Vec<usize>, Vec<f32>, Vec<f32>), row: &mut [f32]| {
        pass_1d(row, out, v, z);
        for (c, d2) in row.iter_mut().zip(out.iter()) {
            *c = if *d2 >= INF { f32::INFINITY } else { d2.sqrt() };
        }
    };
    if nx * ny < SERIAL_BELOW {
        let mut s = scratch();
        g.chunks_mut(nx).for_each(|row| row_pass(&mut s, row));
    } else {
        g.par_chunks_mut(nx).for_each_init(scratch, row_pass);
    }
    g
}

/// Grids smaller than this many cells are transformed on the calling thread: waking the
/// thread pool costs more than the work (the lateral search's coarse grid, a few 10⁴ cells,
/// spent three quarters of its time handing out rows).
const SERIAL_BELOW: usize = 1 << 18;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matches_brute_force() {
        let (nx, ny) = (37, 23);
        let mut site = vec![false; nx * ny];
        let mut s: u64 = 7;
        for v in site.iter_mut() {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1);
            *v = (s >> 60) == 0;
        }
        let d = distance(&site, nx, ny);
        for j in 0..ny {
            for i in 0..nx {
                let mut best = f32::INFINITY;
                for jj in 0..ny {
                    for ii in 0..nx {
                        if site[jj * nx + ii] {
                            let dd = (((i as i64 - ii as i64).pow(2) + (j as i64 - jj as i64).pow(2)) as f32).sqrt();
                            best = best.min(dd);
                        }
                    }
                }
                assert!((d[j * nx + i] - best).abs() < 1e-3, "({i},{j}) {} vs {best}", d[j * nx + i]);
            }
        }
        assert!(distance(&[false; 6], 3, 2).iter().all(|x| x.is_infinite()));
    }
}
