use stochastic_collision::deform::Whirl;
use stochastic_collision::prelude::*;
use stochastic_collision::tracking::*;
fn main() {
    let m = TriMesh::from_obj(std::env::args().nth(1).unwrap()).unwrap();
    let whirl = Whirl::new(&m, 120, 1);
    let mut s = TrackedSurface::new(m.clone());
    let mut tr = Tracker::new(TrackerConfig {
        pairs_per_frame: 64,
        ..TrackerConfig::for_surface(&s)
    });
    let mut p = Vec::new();
    let frames: Vec<Vec<Vec3>> = (0..120)
        .map(|f| {
            whirl.positions(f, &mut p);
            p.clone()
        })
        .collect();
    let t = std::time::Instant::now();
    let (mut it, mut ev, mut act, mut con) = (0, 0, 0, 0);
    for f in &frames {
        s.set_positions(f).unwrap();
        tr.step_self(&s);
        let st = tr.stats();
        it += st.iterations;
        ev += st.evaluations;
        act += st.active;
        con += st.contacts;
    }
    println!(
        "{:.0} us/frame; per frame: {} iterations {} evaluations {} active {} contacts",
        t.elapsed().as_secs_f64() * 1e6 / 120.0,
        it / 120,
        ev / 120,
        act / 120,
        con / 120
    );
}
