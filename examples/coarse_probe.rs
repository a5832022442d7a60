//! How well a coarser lattice would carry the tissue's shape: plays the meninges exercise with the
//! careful script at a resolution up to a step (by default 512 × 384 to step 1 450, in the final lift),
//! keeps every `f`-th element of each layer along both axes (and the last), fills the rest in
//! bilinearly, and prints for each `f` and layer how far the filled-in shape lies from the simulated
//! one (largest and 99th-percentile height error over the elements the exercise moved, as a share of
//! the layer's lift) and the largest stretch of the layer's links in both (against the material's
//! limit). A small error and no link past its limit at `f` = 2 or 4 says that a multi-resolution
//! ChainMail could move the smooth parts of the tent at that coarser spacing and fill in the fine
//! elements, so that a step's work follows what the tent's shape needs rather than the element count.
//!
//! `cargo run --release --example coarse_probe -- 512 384 1450 2,4,8`
use dissect::chainmail::ElementId;
use dissect::runner::Player;
use dissect::scene::{Scene, Script};

const MENINGES: &str = include_str!("../scenes/meninges.ron");
const CAREFUL: &str = include_str!("../scenes/scripts/meninges_careful.ron");

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let arg = |i: usize, d: u32| std::env::args().nth(i).and_then(|a| a.parse().ok()).unwrap_or(d);
    let (nu, nv, until) = (arg(1, 512) as usize, arg(2, 384) as usize, u64::from(arg(3, 1450)));
    let factors: Vec<usize> = std::env::args()
        .nth(4)
        .map(|a| a.split(',').filter_map(|f| f.trim().parse().ok()).filter(|&f| f >= 2).collect())
        .unwrap_or_else(|| vec![2, 4, 8]);
    let _pool = dissect::chainmail::worker_pool("probe")?;
    let scene = Scene::from_str(MENINGES, "scenes/meninges.ron")?.with_resolution(nu as u32, nv as u32);
    let script = Script::from_str(CAREFUL, "meninges_careful.ron")?;
    let mut world = scene.build_world(false)?;
    let mut player = Player::new(script.0.clone());
    while world.step_count() < until {
        player.feed(&mut world);
        if player.finished() && world.pending().is_empty() {
            break;
        }
        world.step();
    }
    let tissue = world.tissue();
    let lat = tissue.body().lattice();
    println!("{nu} x {nv}, step {}", world.step_count());
    for layer in tissue.layers() {
        if layer.count as usize != nu * nv {
            return Err(format!("layer {} has {} elements, not {nu} x {nv}", layer.name, layer.count).into());
        }
        let at = |u: usize, v: usize| ElementId(layer.first + (v * nu + u) as u32);
        let world_of = |u, v| tissue.world_position(at(u, v)).unwrap_or([0.0; 3]).map(f64::from);
        let rest_of = |u: usize, v: usize| {
            let r = lat.rest_positions().get(at(u, v).index()).copied().unwrap_or([0.0; 3]);
            tissue.geometry().to_world(r).map(f64::from)
        };
        let now: Vec<[f64; 3]> =
            (0..nv).flat_map(|v| (0..nu).map(move |u| (u, v))).map(|(u, v)| world_of(u, v)).collect();
        let rest: Vec<[f64; 3]> =
            (0..nv).flat_map(|v| (0..nu).map(move |u| (u, v))).map(|(u, v)| rest_of(u, v)).collect();
        let moved: Vec<bool> = now.iter().zip(&rest).map(|(p, r)| (p[1] - r[1]).abs() > 1e-6).collect();
        let lift = now.iter().zip(&rest).map(|(p, r)| p[1] - r[1]).fold(0.0f64, f64::max);
        let limit = layer_limit(tissue, layer.first);
        let largest = |field: &[[f64; 3]]| largest_stretch(field, &rest, nu, nv);
        println!(
            "  {}: lift {:.2} mm, {} of {} elements moved, largest stretch {:.3} (limit {:.2})",
            layer.name,
            lift * 1e3,
            moved.iter().filter(|&&m| m).count(),
            nu * nv,
            largest(&now),
            limit
        );
        for &f in &factors {
            let filled = fill_in(&now, nu, nv, f);
            let mut err: Vec<f64> = filled
                .iter()
                .zip(&now)
                .zip(&moved)
                .filter(|(_, m)| **m)
                .map(|((q, p), _)| (q[1] - p[1]).abs())
                .collect();
            err.sort_by(f64::total_cmp);
            let max = err.last().copied().unwrap_or(0.0);
            let p99 = err.get(err.len().saturating_sub(1) * 99 / 100).copied().unwrap_or(0.0);
            // The elements a coarser lattice would have to keep fine: those the filling-in misses by
            // more than a few micrometres.
            let over = |um: f64| err.iter().filter(|&&e| e > um * 1e-6).count();
            println!(
                "    every {f}: height error largest {:.1} um ({:.2} % of the lift), p99 {:.1} um; largest stretch {:.3}; \
                 off by more than 2 / 5 / 20 um: {} / {} / {} elements",
                max * 1e6,
                100.0 * max / lift.max(1e-12),
                p99 * 1e6,
                largest(&filled),
                over(2.0),
                over(5.0),
                over(20.0)
            );
            // A coarser lattice of blocks (the cells between kept elements) would keep whole blocks
            // fine: those with an element missed by more than the tolerance.
            let maps = [20.0, 50.0].map(|um| (um, cell_map(&filled, &now, &moved, nu, nv, f, um * 1e-6)));
            for (um, off) in &maps {
                let (cells, elements) = cells_off(off, nu, nv, f);
                println!(
                    "      cells of {f} x {f} with an element off by more than {um} um: {cells} ({elements} elements)"
                );
            }
            // The step's disturbed region in this layer, and how much of it lies in cells the
            // filling-in meets within 50 um (what a scan of cells would not walk element by element).
            let region: Vec<usize> = tissue
                .active_elements()
                .iter()
                .filter_map(|e| e.0.checked_sub(layer.first).filter(|&i| i < layer.count))
                .map(|i| i as usize)
                .collect();
            let off = &maps[1].1;
            let cu = nu.div_ceil(f);
            let inside = region.iter().filter(|&&i| !off[(i / nu / f) * cu + (i % nu) / f]).count();
            println!(
                "      the region: {} of the layer's elements, {inside} in cells met within 50 um",
                region.len()
            );
        }
    }
    Ok(())
}

/// The stretch limit of the layer's links (the material of the link from its first element along `u`).
fn layer_limit(tissue: &dissect::tissue::Tissue, first: u32) -> f64 {
    let body = tissue.body();
    let link = body.lattice().neighbours(ElementId(first)).find(|&(m, _)| m.0 == first + 1).map(|(_, l)| l);
    link.and_then(|l| body.link_material(l))
        .and_then(|m| body.materials().get(m.index()))
        .and_then(|m| match m.limits {
            dissect::chainmail::Limits::Relative { max_stretch, .. } => Some(f64::from(max_stretch)),
            dissect::chainmail::Limits::Absolute { .. } => None,
        })
        .unwrap_or(f64::INFINITY)
}

/// The largest stretch of a layer's links along `u` and `v` (world length over rest length).
fn largest_stretch(field: &[[f64; 3]], rest: &[[f64; 3]], nu: usize, nv: usize) -> f64 {
    let len = |a: [f64; 3], b: [f64; 3]| {
        ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
    };
    let mut largest = 0.0f64;
    for v in 0..nv {
        for u in 0..nu {
            let i = v * nu + u;
            for j in [(u + 1 < nu).then_some(i + 1), (v + 1 < nv).then_some(i + nu)].into_iter().flatten() {
                largest = largest.max(len(field[i], field[j]) / len(rest[i], rest[j]).max(1e-12));
            }
        }
    }
    largest
}

/// How many cells of `off` (a [`cell_map`]) are marked, and how many elements those cells hold.
fn cells_off(off: &[bool], nu: usize, nv: usize, f: usize) -> (usize, usize) {
    let (cu, cv) = (nu.div_ceil(f), nv.div_ceil(f));
    let cells = off.iter().filter(|&&o| o).count();
    let size = |c: usize, n: usize| (n - c * f).min(f);
    let elements = (0..cv)
        .flat_map(|j| (0..cu).map(move |i| (i, j)))
        .filter(|&(i, j)| off[j * cu + i])
        .map(|(i, j)| size(i, nu) * size(j, nv))
        .sum();
    (cells, elements)
}

/// For each cell between kept elements (every `f`-th along both axes: `f × f` elements, row by row),
/// whether it holds a moved element whose height `filled` misses by more than `tol`.
fn cell_map(
    filled: &[[f64; 3]],
    field: &[[f64; 3]],
    moved: &[bool],
    nu: usize,
    nv: usize,
    f: usize,
    tol: f64,
) -> Vec<bool> {
    let (cu, cv) = (nu.div_ceil(f), nv.div_ceil(f));
    let mut off = vec![false; cu * cv];
    for v in 0..nv {
        for u in 0..nu {
            let i = v * nu + u;
            if moved[i] && (filled[i][1] - field[i][1]).abs() > tol {
                off[(v / f) * cu + u / f] = true;
            }
        }
    }
    off
}

/// The field kept at every `f`-th element along both axes (and the last) and filled in bilinearly.
fn fill_in(field: &[[f64; 3]], nu: usize, nv: usize, f: usize) -> Vec<[f64; 3]> {
    let kept = |n: usize| -> Vec<usize> {
        let mut k: Vec<usize> = (0..n).step_by(f).collect();
        if k.last() != Some(&(n - 1)) {
            k.push(n - 1);
        }
        k
    };
    // For each index, the kept indices on either side and the weight of the upper one.
    let bracket = |n: usize| -> Vec<(usize, usize, f64)> {
        let k = kept(n);
        (0..n)
            .map(|i| {
                let j = k.partition_point(|&x| x < i);
                match k.get(j) {
                    Some(&x) if x == i => (i, i, 0.0),
                    Some(&hi) => {
                        let lo = k[j - 1];
                        (lo, hi, (i - lo) as f64 / (hi - lo) as f64)
                    }
                    None => (i, i, 0.0),
                }
            })
            .collect()
    };
    let (bu, bv) = (bracket(nu), bracket(nv));
    let mix = |a: [f64; 3], b: [f64; 3], t: f64| [0, 1, 2].map(|k| (1.0 - t) * a[k] + t * b[k]);
    let mut out = Vec::with_capacity(field.len());
    for &(v0, v1, tv) in &bv {
        for &(u0, u1, tu) in &bu {
            let row = |v: usize| mix(field[v * nu + u0], field[v * nu + u1], tu);
            out.push(mix(row(v0), row(v1), tv));
        }
    }
    out
}
