"""urdyn: URDF-driven rigid multibody dynamics, the Rust engine from numpy.

Pinocchio's names where it has one::

    import numpy as np, urdyn
    model = urdyn.Model.from_urdf("ur5.urdf")
    data = model.create_data()
    q = model.neutral(); v = np.zeros(model.nv); a = np.zeros(model.nv)
    tau = urdyn.rnea(model, data, q, v, a)

Every vector is a 1-D float64 array in the engine's order (a floating base first:
position, quaternion xyzw; velocities in the body frame). A wrong length, a
non-finite number or an unknown name raises ValueError with the CLI's one-line
message; a diverging simulation raises urdyn.SimulationError.
"""

from ._urdyn import (  # noqa: F401
    Data,
    Model,
    Scene,
    Simulation,
    SimulationError,
    aba,
    center_of_mass,
    center_of_mass_jacobian,
    centroidal_momentum,
    crba,
    forward_dynamics,
    forward_dynamics_rnea,
    frame_jacobian,
    frame_placement,
    frame_velocity,
    integrators,
    kinetic_energy,
    nonlinear_effects,
    potential_energy,
    rnea,
    rollout,
)

__all__ = [
    "Data",
    "Model",
    "Scene",
    "Simulation",
    "SimulationError",
    "aba",
    "center_of_mass",
    "center_of_mass_jacobian",
    "centroidal_momentum",
    "crba",
    "forward_dynamics",
    "forward_dynamics_rnea",
    "frame_jacobian",
    "frame_placement",
    "frame_velocity",
    "integrators",
    "kinetic_energy",
    "nonlinear_effects",
    "potential_energy",
    "rnea",
    "rollout",
]
