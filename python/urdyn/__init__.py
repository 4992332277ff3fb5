"""urdyn: URDF-driven rigid multibody dynamics, the Rust engine from numpy.

Pinocchio's names where it has one::

    import numpy as np, urdyn
    model = urdyn.Model.from_urdf("ur5.urdf")
    data = model.create_data()
    q = model.neutral(); v = np.zeros(model.nv); a = np.zeros(model.nv)
    tau = urdyn.rnea(model, data, q, v, a)

Every vector is a 1-D float64 array in the engine's order, which is Pinocchio's (a
floating base first: position, quaternion xyzw; velocities in the body frame; then
the joints as pin.buildModelFromUrdf orders them). A continuous joint is one angle
here and (cos, sin) in Pinocchio's q, a planar joint's (x, y, θ) is (x, y, cos θ,
sin θ) there: from_pinocchio_q / to_pinocchio_q convert. An MJCF model
(Model.from_mjcf, Model.from_file) keeps MuJoCo's order with xyzw quaternions:
from_mujoco_qpos / to_mujoco_qpos / from_mujoco_qvel / to_mujoco_qvel convert. A
wrong length, a non-finite number, a quaternion (a floating base's, a spherical or
inner free joint's) off unit norm (by more than 1e-3) or an unknown name raises ValueError with the CLI's one-line message; a file
that does not exist raises FileNotFoundError; a diverging simulation raises
urdyn.SimulationError.
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
    from_pinocchio_q,
    integrators,
    kinetic_energy,
    linearize,
    nonlinear_effects,
    potential_energy,
    rnea,
    rollout,
    to_pinocchio_q,
    write_html,
)
from ._urdyn import (  # noqa: F401
    aba_derivatives,
    difference,
    frame_jacobian_time_variation,
    integrate,
    random_configuration,
    rnea_derivatives,
)
from ._urdyn import (  # noqa: F401
    Constraints,
    constraint_dynamics,
    constraint_dynamics_derivatives,
    constraint_jacobian,
    constraint_violation,
    from_mujoco_qpos,
    from_mujoco_qvel,
    to_mujoco_qpos,
    to_mujoco_qvel,
)



class _Reading(float):
    """A number read from a simulation now (`sim.constraint_violation`): a float;
    calling it, `sim.constraint_violation()`, gives the same number."""

    __slots__ = ()

    def __call__(self):
        return float(self)

    def __repr__(self):
        return float.__repr__(self)


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
    "from_pinocchio_q",
    "integrators",
    "kinetic_energy",
    "linearize",
    "nonlinear_effects",
    "potential_energy",
    "rnea",
    "rollout",
    "to_pinocchio_q",
    "write_html",
    "aba_derivatives",
    "difference",
    "frame_jacobian_time_variation",
    "integrate",
    "random_configuration",
    "rnea_derivatives",
    "Constraints",
    "constraint_dynamics",
    "constraint_dynamics_derivatives",
    "constraint_jacobian",
    "constraint_violation",
    "from_mujoco_qpos",
    "from_mujoco_qvel",
    "to_mujoco_qpos",
    "to_mujoco_qvel",
]
