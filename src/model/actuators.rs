//! Actuators as a model file gives them (MJCF's `<actuator>`, mjcf.md): each a
//! force f = (g₀ + g₁L + g₂L̇)·u + b₀ + b₁L + b₂L̇ on one 1-DoF joint, L = gear·q,
//! the joint's generalized force gear·f (docs/theory.md §"MJCF actuators").
//! A URDF has none. The simulation sets them from a control vector u
//! (`Simulation::set_controls`).

/// One actuator, in the file's order (MuJoCo's `actuator_*` of one actuator).
#[derive(Clone, Debug, PartialEq)]
pub struct Actuator {
    /// Its name (`actuator_K` when unnamed).
    pub name: String,
    /// The v coordinate (and q coordinate) of the 1-DoF joint it drives;
    /// `None`: not modelled (its control is read and has no effect; the import
    /// report says why).
    pub dof: Option<(usize, usize)>,
    /// Without `dof`: a constant-force actuator on a fixed tendon over several
    /// joints, its generalized force per unit force (v coordinate, gear·coef);
    /// empty otherwise (MJCF `<tendon><fixed>`, src/mjcf/tendons.rs).
    pub moment: Vec<(usize, f64)>,
    /// L = gear·q; the joint's force gear·f.
    pub gear: f64,
    /// The affine gain (g₀, g₁, g₂).
    pub gain: [f64; 3],
    /// The affine bias (b₀, b₁, b₂).
    pub bias: [f64; 3],
    /// The control's range when limited (u is clamped into it).
    pub ctrlrange: Option<(f64, f64)>,
    /// The force's range when limited (f is clamped into it).
    pub forcerange: Option<(f64, f64)>,
}

/// A named starting state of the file (MJCF's `<keyframe><key>`), in urdyn's
/// q and v.
#[derive(Clone, Debug, PartialEq)]
pub struct Keyframe {
    /// Its name (`key_K` when unnamed).
    pub name: String,
    /// Configuration (nq).
    pub q: nalgebra::DVector<f64>,
    /// Velocity (nv).
    pub v: nalgebra::DVector<f64>,
    /// Controls (nu), if the key gives them.
    pub ctrl: Option<Vec<f64>>,
}
