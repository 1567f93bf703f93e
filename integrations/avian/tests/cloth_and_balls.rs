//! The scene, briefly: every ball comes to rest on the cloth (none falls through it, none
//! sinks far into it), and the cloth is pushed down where they rest.
use stochastic_collision_avian::{BALLS, RADIUS, cloth_and_balls_app, positions};

#[test]
fn avian_balls_rest_on_the_deforming_cloth() {
    let mut app = cloth_and_balls_app();
    for _ in 0..150 {
        app.update();
    }
    let (balls, cloth) = positions(&mut app);
    assert_eq!(balls.len(), BALLS);
    let dip = cloth.iter().map(|p| p.y).fold(0.0f32, f32::min);
    for b in &balls {
        // Resting on the cloth: the centre about a radius above the (dipped) surface.
        assert!(b.y > dip && b.y < 0.5, "a ball at {b}, cloth down to {dip}");
        assert!(b.y > RADIUS * 0.25, "sunk into the cloth: {b}");
    }
    // About a hundredth of a unit: cloth vertices that get inside a ball push it back up (the
    // contacts of a deformable's vertices inside a closed partner), so the balls sink less.
    assert!(dip < -0.005, "the balls push the cloth down: {dip}");
}
