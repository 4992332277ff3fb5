//! Diagnostic: a pile scene with sleep on (`urdyn simulate --scene FILE`),
//! per window of `WINDOW` s (default 0.25): awake models, the islands of the
//! awake models (contact points joining two trees), the largest one (models,
//! points), the solve's work and sweeps a step, ms a step; at the end, each
//! awake model's point speed (|v| + |ω| r, r the box's half diagonal), how
//! long it has been still, and its island.
//! `cargo run --release --features tools --example pile_probe FILE [T1]`
//! (env: NOSLEEP=1 sleep off).
use urdyn::scene::Scene;
use urdyn::sim::{SimOptions, Simulation};

#[allow(clippy::needless_range_loop)]
fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let file = args.get(1).ok_or("usage: pile_probe FILE [T1]")?;
    let t1: f64 = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(4.0);
    let w: f64 = std::env::var("WINDOW")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(0.25);
    let scene = Scene::from_file(file, &[])?;
    let opts = SimOptions {
        sleep: std::env::var_os("NOSLEEP").is_none(),
        ..SimOptions::of_scene(&scene)
    };
    let mut sim = Simulation::new_at(scene.model.clone(), opts, &scene.q0, &scene.v0)?;
    let model = sim.model.clone();
    let nt = model.trees.len();
    let mut tree_of_body = vec![usize::MAX; model.nbodies];
    for (t, tr) in model.trees.iter().enumerate() {
        for b in tr.bodies.clone() {
            tree_of_body[b] = t;
        }
    }
    let mut still = vec![0.0f64; nt];
    let (mut work0, mut sweeps0, mut steps, mut most) = (0u64, 0u64, 0u64, 0u64);
    let mut next = w;
    let mut clock = std::time::Instant::now();
    let mut parent: Vec<usize> = (0..nt).collect();
    fn find(p: &mut [usize], mut t: usize) -> usize {
        while p[t] != t {
            p[t] = p[p[t]];
            t = p[t];
        }
        t
    }
    let speed = |sim: &Simulation, t: usize| -> f64 {
        let v = sim.v();
        let r = model.trees[t].v.start;
        let lin = (v[r] * v[r] + v[r + 1] * v[r + 1] + v[r + 2] * v[r + 2]).sqrt();
        let ang = (v[r + 3] * v[r + 3] + v[r + 4] * v[r + 4] + v[r + 5] * v[r + 5]).sqrt();
        lin + ang * 0.0866
    };
    while sim.time() < t1 - 1e-9 {
        let s0 = sim.pgs_sweeps;
        sim.step()?;
        steps += 1;
        most = most.max(sim.pgs_sweeps - s0);
        for (t, s) in still.iter_mut().enumerate() {
            *s = if speed(&sim, t) < 1e-3 {
                *s + sim.dt()
            } else {
                0.0
            };
        }
        if sim.time() >= next - 1e-9 {
            let ms = clock.elapsed().as_secs_f64() * 1e3 / steps as f64;
            for (i, p) in parent.iter_mut().enumerate() {
                *p = i;
            }
            let mut pts = vec![0usize; nt];
            for p in sim.contact_points() {
                let (a, b) = (
                    tree_of_body[p.body],
                    *tree_of_body.get(p.other).unwrap_or(&usize::MAX),
                );
                if a == usize::MAX {
                    continue;
                }
                if b != usize::MAX && a != b {
                    let (ra, rb) = (find(&mut parent, a), find(&mut parent, b));
                    if ra != rb {
                        parent[ra.max(rb)] = ra.min(rb);
                    }
                }
            }
            for p in sim.contact_points() {
                let a = tree_of_body[p.body];
                if a != usize::MAX && !sim.sleeping(&model.trees[a].name).unwrap_or(false) {
                    let r = find(&mut parent, a);
                    pts[r] += 1;
                }
            }
            let mut size = vec![0usize; nt];
            for t in 0..nt {
                if !sim.sleeping(&model.trees[t].name).unwrap_or(false) {
                    let r = find(&mut parent, t);
                    size[r] += 1;
                }
            }
            let mut kinds = [0usize; 3];
            let mut fast = [0.0f64; 3];
            for t in 0..nt {
                let k = model.trees[t]
                    .name
                    .trim_start_matches('o')
                    .parse::<usize>()
                    .unwrap_or(0)
                    % 3;
                let s = speed(&sim, t);
                if s > 1e-3 {
                    kinds[k] += 1;
                }
                fast[k] = fast[k].max(s);
            }
            let islands = size.iter().filter(|&&s| s > 0).count();
            let big = (0..nt).max_by_key(|&r| size[r]).unwrap_or(0);
            let mut sizes: Vec<usize> = size.iter().copied().filter(|&s| s > 0).collect();
            sizes.sort_unstable_by(|a, b| b.cmp(a));
            sizes.truncate(6);
            println!(
                "{:?} t {:.2} awake {} islands {} largest {} models {} pts (sizes {:?}) work/step {:.0} sweeps/step {:.2} max {} ms/step {:.3} moving by k%3 {:?} max {:.1e} {:.1e} {:.1e}",
                std::time::Instant::now(),
                sim.time(),
                sim.awake(),
                islands,
                size[big],
                pts[big],
                sizes,
                (sim.solve_work() - work0) as f64 / steps as f64,
                (sim.pgs_sweeps - sweeps0) as f64 / steps as f64,
                most,
                ms,
                kinds,
                fast[0],
                fast[1],
                fast[2]
            );
            work0 = sim.solve_work();
            sweeps0 = sim.pgs_sweeps;
            steps = 0;
            most = 0;
            next += w;
            clock = std::time::Instant::now();
        }
    }
    println!("mean awake {:.2}", sim.mean_awake());
    for t in 0..nt {
        if !sim.sleeping(&model.trees[t].name).unwrap_or(false) {
            let r = find(&mut parent, t);
            let pos = &sim.q().as_slice()[model.trees[t].q.start..model.trees[t].q.start + 3];
            println!(
                "awake {} island {} speed {:.3e} still {:.3} s at ({:.3}, {:.3}, {:.3})",
                model.trees[t].name,
                model.trees[r].name,
                speed(&sim, t),
                still[t],
                pos[0],
                pos[1],
                pos[2]
            );
        }
    }
    Ok(())
}
