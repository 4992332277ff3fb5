// The README's example verbatim (tests/doc_examples.rs checks that it is): edit both.
use urdyn::sim::{SimOptions, Simulation};
use urdyn::LoadOptions;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let model = urdyn::load_file("assets/lamp.urdf", LoadOptions { floating_base: true })?;
    let mut sim = Simulation::new(model, SimOptions::default())?; // ground contact on
    let (mut q, v) = (sim.q().clone(), sim.v().clone());
    q[2] = 0.5; // base height
    sim.set_state(&q, &v)?;
    while sim.time() < 3.0 {
        sim.torques_mut().fill(0.0); // a controller sets joint torques here
        sim.step()?; // a diverging run is an Err (SimError::Diverging), never a blown-up state
    }
    println!("{} J, {} contacts", sim.energy(), sim.active_contacts());
    for (link, f) in sim.link_contact_forces() {
        println!("{link}: {:?} N at {:?}", f.force, f.point.point); // per contact point
    }
    Ok(())
}
