//! The mechanism examples' checks (docs/mechanisms_examples.md): the four-bar
//! against an independent reference, the held quadruped's tracking and weight,
//! the Luxo lamp's loops. The examples' integrator and set-ups are compiled here
//! once, from examples/common/.

#[path = "../examples/common/constrained.rs"]
mod constrained;
mod four_bar;
#[path = "../examples/common/four_bar_setup.rs"]
mod four_bar_setup;
mod luxo;
mod quadruped_held;
#[path = "../examples/common/quadruped_setup.rs"]
mod quadruped_setup;
