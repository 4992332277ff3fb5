//! `urdyn simulate`'s stepping loop: the simulation steps, a writer thread
//! formats the trajectory CSV, the replay page's recorder takes its frames.

use super::{SimulateError, Summary};
use crate::cli::simulate_mjcf::ControlSchedule;
use crate::cli::view::Recorder;
use crate::sim::{column_names, SimError, Simulation};
use std::io::Write;
use std::time::Instant;

/// What the stepping loop runs and records.
pub(super) struct Run<'a> {
    /// The simulation, set up and at its start state.
    pub sim: &'a mut Simulation,
    /// MJCF actuator controls applied as time reaches them.
    pub schedule: Option<&'a mut ControlSchedule>,
    /// The replay page's frames (`--html`).
    pub recorder: Option<&'a mut Recorder>,
    /// The file named in messages.
    pub name: &'a str,
    /// Simulated seconds.
    pub duration: f64,
    /// Write every Nth step.
    pub every: usize,
    /// Show a progress bar.
    pub progress: bool,
}

/// Steps `run.sim` to `run.duration`, handing the rows to `w` (when given) and
/// the frames to the recorder; returns the summary.
pub(super) fn record(
    run: &mut Run<'_>,
    w: Option<&mut (dyn Write + Send)>,
) -> Result<Summary, SimulateError> {
    let Run {
        sim,
        schedule,
        recorder,
        name: urdf_name,
        duration,
        every,
        progress,
    } = run;
    let (sim, duration, every) = (&mut **sim, *duration, *every);
    let urdf_name: &str = urdf_name;
    let has_loops = sim.has_constraints();
    let progress = if *progress && duration > 0.0 {
        let pb = indicatif::ProgressBar::new(1000);
        pb.set_style(
            indicatif::ProgressStyle::with_template(
                "{bar:40} {percent:>3}% t = {msg} s  eta {eta}",
            )
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
        );
        Some(pb)
    } else {
        None
    };

    // The simulation thread hands raw rows (t, q, v, energy, contacts,
    // penetration) in blocks to a writer thread, which formats the CSV: the step
    // loop never formats a number. (The energy is computed here, from the
    // kinematics the step's contact detection left, at a fraction of its cost
    // in the writer.) Blocks are recycled (no allocation once both are in
    // flight), the channel is bounded (the writer cannot fall behind by more
    // than a few blocks).
    let (nq, nv) = (sim.model.nq, sim.model.nv);
    let width = row_width(nq, nv) + usize::from(has_loops);
    let header = {
        let (qn, vn) = column_names(&sim.model);
        let mut h = String::from("t");
        for n in qn.iter().chain(vn.iter()) {
            h.push(',');
            h.push_str(n);
        }
        h.push_str(",energy,contacts,penetration,awake");
        if has_loops {
            h.push_str(",constraint_violation");
        }
        h.push('\n');
        h
    };
    let block_rows = 256usize;
    let e0 = sim.energy();
    let mut max_pen = sim.penetration();
    let mut max_viol = if has_loops {
        sim.constraint_violation()
    } else {
        0.0
    };
    // the clock starts inside the scope, once the writer is set up
    let start = std::thread::scope(|scope| {
        let (to_writer, from_sim) = std::sync::mpsc::sync_channel::<Vec<f64>>(4);
        let (recycle, recycled) = std::sync::mpsc::channel::<Vec<f64>>();
        // set-up, not stepping: the writer thread is started and the blocks
        // in flight are allocated and touched (their pages faulted in)
        // before the clock starts
        let touched = || {
            let mut b = vec![0.0f64; width * block_rows];
            b.clear();
            b
        };
        let writer = w.map(|w| {
            for _ in 0..BLOCKS_IN_FLIGHT {
                let _ = recycle.send(touched());
            }
            scope.spawn(|| write_rows(w, &header, (nq, nv, has_loops), from_sim, recycle))
        });
        let mut block: Vec<f64> = touched();
        let start = Instant::now();
        let push_row = |sim: &mut Simulation,
                        block: &mut Vec<f64>,
                        recorder: &mut Option<&mut Recorder>,
                        last: bool|
         -> Result<(), SimulateError> {
            let e = finite_energy(sim, urdf_name)?;
            block.push(sim.time());
            block.extend_from_slice(sim.q().as_slice());
            block.extend_from_slice(sim.v().as_slice());
            block.push(e);
            block.push(sim.active_contacts() as f64);
            block.push(sim.penetration());
            block.push(sim.awake() as f64);
            if has_loops {
                let c = sim.constraint_violation();
                block.push(c);
            }
            if let Some(r) = recorder {
                let plot = [e, sim.active_contacts() as f64, sim.penetration()];
                r.offer_with(sim.time(), sim.q(), plot, last, |out| {
                    out.extend(sim.contact_forces().iter().map(|c| {
                        crate::cli::view::ContactArrow {
                            point: c.point.point.into(),
                            force: c.force.into(),
                        }
                    }))
                });
            }
            Ok(())
        };
        // sends a full block (or, at the end, the last one); a writer that hung
        // up has failed: its error is collected at the join below
        let send = |block: &mut Vec<f64>| -> bool {
            if writer.is_none() {
                block.clear();
                return true;
            }
            let next = recycled
                .try_recv()
                .unwrap_or_else(|_| Vec::with_capacity(width * block_rows));
            to_writer.send(std::mem::replace(block, next)).is_ok()
        };
        let mut sim_result = push_row(sim, &mut block, recorder, duration <= 0.0);
        let mut k = 0u64;
        let mut last_tick = 0u64;
        while sim_result.is_ok() && sim.time() < duration {
            let t_stop = match schedule.as_mut().map(|s| s.apply_due(sim)) {
                None => duration,
                Some(Ok(t)) => t.min(duration),
                Some(Err(error)) => {
                    sim_result = Err(SimulateError::Sim {
                        urdf: urdf_name.to_string(),
                        error,
                    });
                    break;
                }
            };
            if let Err(error) = sim.step_until(t_stop) {
                sim_result = Err(SimulateError::Sim {
                    urdf: urdf_name.to_string(),
                    error,
                });
                break;
            }
            k += 1;
            max_pen = max_pen.max(sim.penetration());
            if has_loops {
                max_viol = max_viol.max(sim.constraint_violation());
            }
            let last = sim.time() >= duration;
            if last || k % every as u64 == 0 {
                if let Err(e) = push_row(sim, &mut block, recorder, last) {
                    sim_result = Err(e);
                    break;
                }
                if block.len() >= width * block_rows && !send(&mut block) {
                    break;
                }
            }
            if let Some(pb) = &progress {
                let tick = (sim.time() / duration * 1000.0) as u64;
                if tick != last_tick {
                    last_tick = tick;
                    pb.set_position(tick);
                    pb.set_message(format!("{:.3}", sim.time()));
                }
            }
        }
        if sim_result.is_ok() && !block.is_empty() {
            send(&mut block);
        }
        drop(to_writer);
        let written = match writer {
            Some(h) => h
                .join()
                .unwrap_or_else(|_| Err(SimulateError::Output("trajectory writer failed".into()))),
            None => Ok(()),
        };
        sim_result?;
        written.map(|()| start)
    })?;
    if let Some(pb) = &progress {
        pb.finish_and_clear();
    }
    let wall = start.elapsed().as_secs_f64();
    let e = finite_energy(sim, urdf_name)?;
    Ok(Summary {
        steps: sim.steps,
        wall_seconds: wall,
        simulated_seconds: sim.time(),
        real_time_factor: if wall > 0.0 {
            sim.time() / wall
        } else {
            f64::INFINITY
        },
        energy_start: e0,
        energy_end: e,
        max_penetration: max_pen,
        integrator: sim.integrator().name(),
        contact_queries: sim.contact_queries(),
        mean_awake: sim.mean_awake(),
        max_constraint_violation: has_loops.then_some(max_viol),
    })
}

/// Blocks of rows allocated for the writer before the stepping starts (the
/// channel holds 4, the writer formats one and the simulation fills one).
const BLOCKS_IN_FLIGHT: usize = 6;

/// Numbers in one raw row handed to the writer: t, q (nq), v (nv), energy,
/// contacts, penetration, awake.
fn row_width(nq: usize, nv: usize) -> usize {
    1 + nq + nv + 4
}

/// The writer thread: the header, then the CSV line of every row.
fn write_rows(
    w: &mut (dyn Write + Send),
    header: &str,
    (nq, nv, has_loops): (usize, usize, bool),
    rows: std::sync::mpsc::Receiver<Vec<f64>>,
    recycle: std::sync::mpsc::Sender<Vec<f64>>,
) -> Result<(), SimulateError> {
    use std::fmt::Write as _;
    let io = |e: std::io::Error| SimulateError::Output(format!("cannot write trajectory: {e}"));
    let width = row_width(nq, nv) + usize::from(has_loops);
    let mut line = String::with_capacity(32 * width + 64);
    w.write_all(header.as_bytes()).map_err(io)?;
    let mut rb = zmij::Buffer::new();
    for block in rows {
        for row in block.chunks_exact(width) {
            let (t, rest) = row.split_at(1);
            let (qs, rest) = rest.split_at(nq);
            let (vs, rest) = rest.split_at(nv);
            let t = t.first().copied().unwrap_or(0.0);
            let (e, contacts, pen, awake) = (
                rest.first().copied().unwrap_or(0.0),
                rest.get(1).copied().unwrap_or(0.0),
                rest.get(2).copied().unwrap_or(0.0),
                rest.get(3).copied().unwrap_or(0.0),
            );
            line.clear();
            line.push_str(rb.format(t));
            for x in qs.iter().chain(vs.iter()) {
                line.push(',');
                line.push_str(rb.format(*x));
            }
            line.push(',');
            line.push_str(rb.format(e));
            line.push(',');
            // (formatting into a String cannot fail)
            let _ = write!(line, "{}", contacts as u64);
            line.push(',');
            line.push_str(rb.format(pen));
            line.push(',');
            let _ = write!(line, "{}", awake as u64);
            if has_loops {
                line.push(',');
                line.push_str(rb.format(rest.get(4).copied().unwrap_or(0.0)));
            }
            line.push('\n');
            w.write_all(line.as_bytes()).map_err(io)?;
        }
        let mut block = block;
        block.clear();
        let _ = recycle.send(block);
    }
    Ok(())
}

/// The energy of the current state, or the error naming its time when it is not
/// finite (q and v are checked by every step; an overflowing energy is not).
fn finite_energy(sim: &mut Simulation, urdf_name: &str) -> Result<f64, SimulateError> {
    let e = sim.energy();
    if e.is_finite() {
        Ok(e)
    } else {
        Err(SimulateError::Sim {
            urdf: urdf_name.to_string(),
            error: SimError::NonFinite {
                t: sim.time(),
                quantity: "energy".into(),
            },
        })
    }
}
