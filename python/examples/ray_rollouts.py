"""Rollouts beyond one machine: a pickled urdyn.Model and batches of initial
states sent to Ray tasks, each calling urdyn.rollout on its own cores.

The same code runs on a laptop (`ray.init()`) and on a cluster
(`RAY_ADDRESS=ray://head:10001 python ray_rollouts.py`, or `ray.init(address=...)`).

    pip install ray
    python python/examples/ray_rollouts.py [ROBOT.urdf] [--floating-base]
"""

import argparse
from pathlib import Path

import numpy as np
import ray

import urdyn


@ray.remote(num_cpus=1)
def run_batch(model, q0, v0, nstep, dt, threads, ground):
    """One Ray task: a batch of rollouts (the model arrives pickled)."""
    return urdyn.rollout(model, q0, v0, nstep=nstep, dt=dt, threads=threads, ground=ground)


def rollouts_on_ray(model, q0, v0, nstep=1000, dt=1e-3, batches=2, threads_per_task=1, ground=0.0):
    """Splits the B initial states into `batches` Ray tasks and stacks their results
    in order: the same arrays as one local `urdyn.rollout(model, q0, v0, ...)`."""
    model_ref = ray.put(model)
    parts = [
        run_batch.remote(model_ref, q, v, nstep, dt, threads_per_task, ground)
        for q, v in zip(np.array_split(q0, batches), np.array_split(v0, batches))
    ]
    results = ray.get(parts)
    return np.concatenate([q for q, _ in results]), np.concatenate([v for _, v in results])


def initial_states(model, batch, seed=0):
    """Random joint angles in [-1, 1] rad, at rest (a floating base 0.3 m up)."""
    rng = np.random.default_rng(seed)
    q0 = np.tile(model.neutral(), (batch, 1))
    off = 7 if model.floating_base else 0
    q0[:, off:] = rng.uniform(-1.0, 1.0, (batch, model.nq - off))
    if model.floating_base:
        q0[:, 2] = 0.3
    return q0, np.zeros((batch, model.nv))


def main():
    root = Path(__file__).resolve().parents[2]
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("urdf", nargs="?", default=str(root / "assets" / "robots" / "ur5.urdf"))
    ap.add_argument("--floating-base", action="store_true")
    ap.add_argument("--batch", type=int, default=8)
    ap.add_argument("--nstep", type=int, default=500)
    ap.add_argument("--address", default=None, help="a Ray cluster (default: start one here)")
    args = ap.parse_args()
    ray.init(address=args.address, num_cpus=None if args.address else 2, include_dashboard=False)
    model = urdyn.Model.from_urdf(args.urdf, floating_base=args.floating_base)
    q0, v0 = initial_states(model, args.batch)
    # a fixed arm needs no ground (and no collision meshes)
    ground = 0.0 if args.floating_base else None
    q, v = rollouts_on_ray(model, q0, v0, nstep=args.nstep, ground=ground)
    local_q, local_v = urdyn.rollout(model, q0, v0, nstep=args.nstep, ground=ground)
    same = np.array_equal(q, local_q) and np.array_equal(v, local_v)
    print(f"{args.batch} rollouts x {args.nstep} steps on Ray: q {q.shape}; equal to the local rollout: {same}")
    ray.shutdown()
    if not same:
        raise SystemExit(1)


if __name__ == "__main__":
    main()
