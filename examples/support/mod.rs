//! Scene code shared by the example worlds (`pile`, `cannonball`, `cloth`, `intestine`,
//! `needle`, `tunnel`) and `profile`: each scene builds a headless `App` with the plugin in
//! `PostUpdate`.
#![allow(dead_code)]

pub mod cannonball;
pub mod cloth;
pub mod intestine;
pub mod needle;
pub mod pile;
pub mod tunnel;

use std::path::PathBuf;
use std::time::Duration;

use bevy_app::prelude::*;
use stochastic_collision::adb::{Decision, Order};
use stochastic_collision::prelude::*;

/// Settings every scene takes (the `profile` command line).
#[derive(Debug, Clone)]
pub struct Options {
    /// Scene-specific count (bodies, shots, cloths, intestines); 0 = the scene's default.
    pub entities: usize,
    /// Threads testing pairs.
    pub threads: usize,
    /// Time budget of the collision stages per run, µs (0 = unlimited).
    pub budget_us: u64,
    /// Work budget in ADB node pairs per run (overrides the time budget: deterministic).
    pub node_budget: Option<u64>,
    /// Seed of the scene and of the plugin.
    pub seed: u64,
    /// Fidelity of rigid colliders without their own (default: ADB with `p_min = 0.99`).
    pub fidelity: Option<Fidelity>,
    /// How ADB queries decide (default: the plugin's).
    pub adb_decision: Option<Decision>,
    /// In which order ADB queries expand node pairs (default: the plugin's).
    pub adb_order: Option<Order>,
    /// Whether ADB queries try the interpenetration certificate first (default: the plugin's).
    pub adb_interior: Option<bool>,
    /// Write a `Contact` message per contact (`CollisionConfig::contact_messages`).
    pub contact_messages: bool,
    /// The cannonball scene's shot speed, a multiple of its default (1).
    pub speed: f32,
    /// The cannonball scene's shots get `ContinuousCollision::WhenFast`.
    pub continuous: bool,
}

impl Default for Options {
    fn default() -> Self {
        Self {
            entities: 0,
            threads: 2,
            budget_us: 2000,
            node_budget: None,
            seed: 1,
            fidelity: None,
            adb_decision: None,
            adb_order: None,
            adb_interior: None,
            contact_messages: false,
            speed: 1.0,
            continuous: false,
        }
    }
}

impl Options {
    /// The plugin's configuration for these options.
    pub fn config(&self) -> CollisionConfig {
        let budget = match (self.node_budget, self.budget_us) {
            (Some(n), _) => FrameBudget::NodePairs(n),
            (None, 0) => FrameBudget::Unlimited,
            (None, us) => FrameBudget::Time(Duration::from_micros(us)),
        };
        let defaults = CollisionConfig::default();
        CollisionConfig {
            budget,
            seed: self.seed,
            default_fidelity: self.fidelity.unwrap_or(defaults.default_fidelity),
            adb_decision: self.adb_decision.unwrap_or(defaults.adb_decision),
            adb_order: self.adb_order.unwrap_or(defaults.adb_order),
            adb_interior: self.adb_interior.unwrap_or(defaults.adb_interior),
            contact_messages: self.contact_messages,
            ..defaults
        }
    }

    /// The plugin in `PostUpdate` (no time plugin needed) with these options.
    pub fn plugin(&self) -> StochasticCollisionPlugin {
        StochasticCollisionPlugin::in_schedule(PostUpdate)
            .with_config(self.config())
            .with_threads(self.threads)
    }

    /// `entities`, or `default` when 0.
    pub fn count(&self, default: usize) -> usize {
        if self.entities == 0 {
            default
        } else {
            self.entities
        }
    }
}

/// The scenes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Scene {
    /// Rigid bodies falling into a box.
    Pile,
    /// Cannonballs against a wall.
    Cannonball,
    /// Cloth draped over a ball.
    Cloth,
    /// A deforming intestine.
    Intestine,
}

impl Scene {
    /// From its name.
    pub fn parse(name: &str) -> Option<Scene> {
        Some(match name {
            "pile" => Scene::Pile,
            "cannonball" => Scene::Cannonball,
            "cloth" => Scene::Cloth,
            "intestine" => Scene::Intestine,
            _ => return None,
        })
    }

    /// Its name.
    pub fn name(self) -> &'static str {
        match self {
            Scene::Pile => "pile",
            Scene::Cannonball => "cannonball",
            Scene::Cloth => "cloth",
            Scene::Intestine => "intestine",
        }
    }

    /// Frames a quick run takes.
    pub fn default_frames(self) -> usize {
        match self {
            Scene::Pile => 300,
            Scene::Cannonball => 150,
            Scene::Cloth => 120,
            Scene::Intestine => 30,
        }
    }

    /// The scene's time budget per run when none is given, µs: 2 ms for the rigid scenes and
    /// the cloth; 30 ms for the 100k-triangle intestine (a surgical simulator's frame: its
    /// refit and tracked-surface update alone would fill a 2 ms budget).
    pub fn default_budget_us(self) -> u64 {
        match self {
            Scene::Pile | Scene::Cannonball | Scene::Cloth => 2000,
            Scene::Intestine => 30_000,
        }
    }

    /// Builds the scene's app.
    pub fn build(self, options: &Options) -> App {
        let mut app = App::new();
        app.add_plugins(options.plugin());
        tally::add(&mut app);
        match self {
            Scene::Pile => pile::setup(&mut app, options),
            Scene::Cannonball => cannonball::setup(&mut app, options, None),
            Scene::Cloth => cloth::setup(&mut app, options),
            Scene::Intestine => intestine::setup(&mut app, options),
        }
        app
    }
}

/// A shared mesh (`../shared/assets/meshes/<file>` beside the crate), if present.
pub fn shared_mesh(file: &str) -> Option<TriMesh> {
    let dir = std::env::var_os("STOCHASTIC_COLLISION_MESHES").map_or_else(
        || PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/assets/meshes"),
        PathBuf::from,
    );
    TriMesh::from_obj(dir.join(file)).ok()
}

pub use pile::layout::normalized;

pub mod tally {
    //! Counting the events a game would read: a reader that runs only every other frame (and
    //! once more at the end), to check that none is lost.
    use bevy_app::prelude::*;
    use bevy_ecs::prelude::*;
    use stochastic_collision::prelude::*;

    /// Events read by [`read_events`].
    #[derive(Resource, Debug, Default, Clone, Copy)]
    pub struct Tally {
        pub started: u64,
        pub ended: u64,
        pub contacts: u64,
        pub errors: u64,
        pub updates: u64,
        /// Set before the last update: the reader runs then whatever the frame.
        pub last: bool,
    }

    pub fn add(app: &mut App) {
        app.init_resource::<Tally>().add_systems(
            Last,
            (
                read_events.run_if(|t: Res<Tally>| t.updates % 2 == 1 || t.last),
                |mut t: ResMut<Tally>| t.updates += 1,
            )
                .chain(),
        );
    }

    fn read_events(
        mut t: ResMut<Tally>,
        mut started: MessageReader<CollisionStarted>,
        mut ended: MessageReader<CollisionEnded>,
        mut contacts: MessageReader<Contact>,
        mut errors: MessageReader<CollisionError>,
    ) {
        t.started += started.read().count() as u64;
        t.ended += ended.read().count() as u64;
        t.contacts += contacts.read().count() as u64;
        t.errors += errors.read().count() as u64;
    }

    /// Events written but not read.
    pub fn lost(world: &World) -> u64 {
        let c = world.resource::<CollisionDiagnostics>().counters;
        let t = world.resource::<Tally>();
        (c.started + c.ended + c.contacts).saturating_sub(t.started + t.ended + t.contacts)
    }
}

/// Writes `svg` to `path`, creating its folder; the error names what failed and where.
pub fn write_svg(path: &std::path::Path, svg: &str) -> Result<PathBuf, String> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)
            .map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    }
    std::fs::write(path, svg).map_err(|e| format!("cannot write {}: {e}", path.display()))?;
    Ok(path.to_path_buf())
}
