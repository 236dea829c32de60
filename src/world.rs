//! The world: fixed-capacity pools of bodies, contacts and events, and the fixed step.

use heapless::Vec as HVec;

use crate::config::WorldConfig;
use crate::dynamics::body::{Body, BodyDesc, BodyKind, Material};
use crate::dynamics::broad_phase::{self, BroadPhase};
use crate::dynamics::contact::{self, Contact};
use crate::dynamics::events::{Event, StepReport};
use crate::dynamics::pool::{BodyHandle, Pool};
use crate::dynamics::snapshot::{Hooks, Stage, StepTrace};
use crate::dynamics::solver::{self, Solver};
use crate::dynamics::{ccd, mid_phase, projection, sleep};
use crate::error::{finite_vec, Error, Input, Pool as PoolKind};
use crate::math::{Iso, Quat, Vec3};
use crate::shape::Shape;

/// A physics world with room for `BODIES` bodies, `CONTACTS` contacts (manifolds, and as
/// many candidate pairs per step) and `EVENTS` events per step.
///
/// Everything lives inline: no heap. A world is large (680 bytes per body slot and 1113
/// per contact slot on 64-bit hosts, README "Capacity"), so where it lives matters:
///
/// - In a `static`: `World::new` is a `const fn`, so the compiler builds the world and
///   it never touches the stack, in debug builds too, without `unsafe`. Its bytes are in
///   the program image.
///
///   ```
///   use std::sync::Mutex;
///   use carom::World;
///
///   static WORLD: Mutex<World<'static, 256, 1024>> = Mutex::new(World::new());
///
///   let mut world = WORLD.lock().unwrap();
///   world.step();
///   ```
/// - In a `Box`: `Box::new(World::new())` builds the world on the stack first. Optimised
///   builds mostly construct it in place (0.4 MB of stack for a 1.4 MB world), but at
///   opt-level 0 it takes about 3.6 times the world's size in stack, so a world over
///   about 2 MB overflows the 8 MB main stack of a debug build. No safe way to fill a
///   `Box` avoids that (README, "Capacity").
/// - On the stack of a thread spawned with a big enough `stack_size`.
///
/// # Examples
///
/// ```
/// use carom::{BodyDesc, Event, Shape, Vec3, World};
///
/// # fn main() -> Result<(), carom::Error> {
/// // 8 bodies, 32 contacts, 16 events per step; small enough for the stack.
/// let mut world: World<'static, 8, 32, 16> = World::new();
/// let ground = world.add(
///     BodyDesc::fixed(Shape::cuboid(Vec3::new(5.0, 0.5, 5.0))?).position(Vec3::new(0.0, -0.5, 0.0)),
/// )?;
/// let ball = world.add(BodyDesc::dynamic(Shape::sphere(0.25)?).position(Vec3::new(0.0, 1.0, 0.0)))?;
/// let mut touched = false;
/// for _ in 0..60 {
///     let report = world.step();
///     assert!(!report.overflowed()); // nothing dropped for lack of room
///     touched |= world.events().iter().any(|e| {
///         matches!(e, Event::ContactBegin { a, b } if [*a, *b] == [ground, ball])
///     });
/// }
/// assert!(touched);
/// assert_eq!(world.body_count(), 2);
/// # Ok(())
/// # }
/// ```
#[derive(Clone, Debug)]
pub struct World<'a, const BODIES: usize, const CONTACTS: usize, const EVENTS: usize = 256> {
    pub(crate) config: WorldConfig,
    pub(crate) bodies: Pool<Body<'a>, BODIES>,
    pub(crate) broad: BroadPhase<BODIES>,
    pub(crate) pairs: HVec<(u32, u32), CONTACTS>,
    pub(crate) contacts: HVec<Contact, CONTACTS>,
    pub(crate) solver: Solver<BODIES, CONTACTS>,
    pub(crate) events: HVec<Event, EVENTS>,
    pub(crate) islands: [u32; BODIES],
    pub(crate) step_count: u64,
    pub(crate) report: StepReport,
    /// Every non-static body sleeps and nothing moved at the end of the last step, and no
    /// call changed anything since: the next step would change nothing but the step
    /// count, so it does only that. Derived state (false after a restore).
    pub(crate) quiet: bool,
}

impl<'a, const BODIES: usize, const CONTACTS: usize, const EVENTS: usize> Default
    for World<'a, BODIES, CONTACTS, EVENTS>
{
    fn default() -> Self {
        Self::new()
    }
}

impl<'a, const BODIES: usize, const CONTACTS: usize, const EVENTS: usize>
    World<'a, BODIES, CONTACTS, EVENTS>
{
    /// An empty world with [`WorldConfig::DEFAULT`]. `const`, so a world can be a `static`.
    pub const fn new() -> Self {
        World {
            config: WorldConfig::DEFAULT,
            bodies: Pool::new(),
            broad: BroadPhase::new(),
            pairs: HVec::new(),
            contacts: HVec::new(),
            solver: Solver::new(),
            events: HVec::new(),
            islands: [0; BODIES],
            step_count: 0,
            report: StepReport {
                awake_bodies: 0,
                pairs: 0,
                contacts: 0,
                points: 0,
                ccd_sweeps: 0,
                ccd_hits: 0,
                ccd_queries: 0,
                dropped_pairs: 0,
                dropped_contacts: 0,
                dropped_events: 0,
            },
            quiet: false,
        }
    }

    /// An empty world with `config`, which is validated first.
    pub fn with_config(config: WorldConfig) -> Result<Self, Error> {
        config.validate()?;
        let mut w = Self::new();
        w.config = config;
        Ok(w)
    }

    /// The configuration.
    pub fn config(&self) -> &WorldConfig {
        &self.config
    }

    /// Replace the configuration (validated; unchanged on error). Existing contacts take
    /// new combine rules at once.
    pub fn set_config(&mut self, config: WorldConfig) -> Result<(), Error> {
        config.validate()?;
        let rules_changed = config.friction_combine != self.config.friction_combine
            || config.restitution_combine != self.config.restitution_combine;
        self.config = config;
        self.quiet = false;
        if rules_changed {
            self.recombine_materials(None);
        }
        Ok(())
    }

    /// Advance the world by one fixed step of `config.dt` seconds.
    pub fn step(&mut self) -> StepReport {
        self.step_with(Hooks::NONE)
    }

    /// [`World::step`], recording a digest of the state after every stage into `trace`:
    /// two peers that compare traces find the first stage where they diverge.
    pub fn step_traced(&mut self, trace: Option<&mut StepTrace>) -> StepReport {
        self.step_with(Hooks {
            trace,
            on_stage: None,
        })
    }

    /// [`World::step`], calling `on_stage` right after each stage ends, once per stage in
    /// the order of [`Stage::ALL`] (a step of a world at rest too): a profiler's hook.
    /// Read a clock in it (a cycle counter on a Cortex-M, `std::time::Instant` on a
    /// host) and the time between two calls is the stage between them; `compare/`'s
    /// `--stages` table is made this way. The callback cannot reach the world, which the
    /// step holds, so the step computes the same as [`World::step`], to the bit.
    pub fn step_observed(&mut self, on_stage: &mut dyn FnMut(Stage)) -> StepReport {
        self.step_with(Hooks {
            trace: None,
            on_stage: Some(on_stage),
        })
    }

    /// The pipeline, one call per stage (DESIGN.md, "One fixed step"); `hooks` hear of
    /// each stage as it ends.
    fn step_with(&mut self, mut hooks: Hooks<'_>) -> StepReport {
        if self.quiet {
            return self.quiet_step(hooks);
        }
        let cfg = self.config;
        let mut report = StepReport::default();
        self.events.clear();
        // 1-2 movement bounds: bodies whose motion leaves their enlarged box get a new one
        broad_phase::update_fat_boxes(&mut self.bodies, &cfg);
        // 3 broad phase: new candidate pairs, searched around moved bodies only
        let (bodies, contacts, pairs) = (&mut self.bodies, &mut self.contacts, &mut self.pairs);
        self.broad
            .find_new_pairs(bodies, contacts, pairs, &mut report);
        contact::insert_pairs(contacts, pairs, bodies, &cfg, &mut report);
        self.stage_done(&mut hooks, Stage::BroadPhase);
        // 4 mid phase: the part pairs of meshes and compounds that may touch
        mid_phase::update_parts(&mut self.contacts, &mut self.bodies, &mut report);
        // 5 narrow phase, 6 contact cache: manifolds reused or rebuilt, warm-started
        let events = &mut self.events;
        contact::update_contacts(
            &mut self.contacts,
            &mut self.bodies,
            &cfg,
            events,
            &mut report,
        );
        self.stage_done(&mut hooks, Stage::NarrowPhase);
        // 7 solve in sub-steps: integrate, warm start, soft contacts, relax, restitution
        let (contacts, scratch) = (&mut self.contacts, &mut self.pairs);
        solver::solve(&mut self.solver, contacts, &mut self.bodies, scratch, &cfg);
        self.stage_done(&mut hooks, Stage::Solve);
        // 8 continuous collision: time of impact for fast bodies
        let (bodies, contacts, pairs) = (&mut self.bodies, &self.contacts, &mut self.pairs);
        let broad = &self.broad;
        ccd::sweep_fast_bodies(bodies, broad, contacts, pairs, &cfg, cfg.dt, &mut report);
        self.stage_done(&mut hooks, Stage::Continuous);
        // 9 projection: bounded push-out of the deep penetration that remains
        projection::project(&mut self.solver, &self.contacts, &mut self.bodies, &cfg);
        self.stage_done(&mut hooks, Stage::Projection);
        // 10 sleep: islands fall asleep and wake together
        report.awake_bodies =
            sleep::update_sleep(&mut self.bodies, &self.contacts, &mut self.islands, &cfg);
        self.step_count = self.step_count.wrapping_add(1);
        self.stage_done(&mut hooks, Stage::Sleep);
        self.report = report;
        self.quiet = report.awake_bodies == 0
            && !self
                .bodies
                .iter()
                .any(|(_, b)| b.moved || (b.kind == BodyKind::Kinematic && b.awake));
        report
    }

    /// A step of a world at rest (see `quiet`): every stage would leave the state as it
    /// is, so only the step count moves; the report and the trace are what the full step
    /// would give.
    fn quiet_step(&mut self, mut hooks: Hooks<'_>) -> StepReport {
        self.events.clear();
        // The broad phase would find no new pair (nothing moved).
        self.pairs.clear();
        // The solver's gather: every pose is the step's start pose, forces are spent.
        for (_, b) in self.bodies.iter_mut() {
            b.pose0 = *b.pose();
            b.force = Vec3::ZERO;
            b.torque = Vec3::ZERO;
        }
        let report = StepReport {
            awake_bodies: 0,
            contacts: self.report.contacts,
            points: self.report.points,
            ..StepReport::default()
        };
        for stage in [
            Stage::BroadPhase,
            Stage::NarrowPhase,
            Stage::Solve,
            Stage::Continuous,
            Stage::Projection,
        ] {
            self.stage_done(&mut hooks, stage);
        }
        self.step_count = self.step_count.wrapping_add(1);
        self.stage_done(&mut hooks, Stage::Sleep);
        self.report = report;
        report
    }

    /// The report of the last step.
    pub fn last_report(&self) -> StepReport {
        self.report
    }

    /// Events of the last step, in the order they happened.
    pub fn events(&self) -> &[Event] {
        &self.events
    }

    /// Empty the world where it lies: afterwards it is what [`World::new`] returns (the
    /// default config, no body, no contact, no event, step 0, every slot's generation 0),
    /// and it steps, hashes and snapshots as a new world does, to the bit. Unlike
    /// `*world = World::new()`, it builds no second world on the stack first: firmware
    /// that keeps its world in a `static` starts a new round or level with it. A handle
    /// from before names the body that takes its slot next, as in a new world.
    pub fn reset(&mut self) {
        // Every field named: a new one cannot be left out.
        let World {
            config,
            bodies,
            broad,
            pairs,
            contacts,
            solver,
            events,
            islands,
            step_count,
            report,
            quiet,
        } = self;
        *config = WorldConfig::DEFAULT;
        bodies.reset();
        broad.reset();
        pairs.clear();
        contacts.clear();
        solver.reset();
        events.clear();
        islands.fill(0);
        *step_count = 0;
        *report = StepReport::default();
        *quiet = false;
    }

    /// Number of steps taken.
    pub fn step_count(&self) -> u64 {
        self.step_count
    }

    /// Number of bodies.
    pub fn body_count(&self) -> usize {
        self.bodies.len()
    }

    /// Number of contacts with at least one point (manifolds) after the last step.
    pub fn contact_count(&self) -> usize {
        self.contacts.iter().filter(|c| c.len > 0).count()
    }

    /// Number of pairs the broad phase tracks (enlarged boxes overlapping), with or
    /// without contact points.
    pub fn pair_count(&self) -> usize {
        self.contacts.len()
    }

    /// Add a body. Fails with the description's first invalid input, or with
    /// `PoolFull(Bodies)`; the world is unchanged on error.
    pub fn add(&mut self, desc: BodyDesc<'a>) -> Result<BodyHandle, Error> {
        let body = Body::from_desc(&desc)?;
        self.quiet = false;
        self.bodies
            .insert(body)
            .ok_or(Error::PoolFull(PoolKind::Bodies))
    }

    /// Remove a body and its contacts (without end events). Bodies it touched wake up,
    /// so nothing stays asleep in the air.
    pub fn remove(&mut self, h: BodyHandle) -> Result<(), Error> {
        self.bodies.get(h).ok_or(Error::StaleHandle)?;
        self.quiet = false;
        self.wake_touching(h.index);
        self.bodies.remove(h).ok_or(Error::StaleHandle)?;
        self.contacts.retain(|c| c.a != h.index && c.b != h.index);
        self.broad.remove_body(h.index);
        Ok(())
    }

    /// Wake every dynamic body that has a contact with slot `slot`.
    fn wake_touching(&mut self, slot: u32) {
        for c in self.contacts.iter() {
            let other = if c.a == slot {
                c.b
            } else if c.b == slot {
                c.a
            } else {
                continue;
            };
            if let Some(b) = self.bodies.at_mut(other as usize) {
                if b.is_dynamic() {
                    wake(b);
                }
            }
        }
    }

    /// Handles of all bodies in slot order.
    pub fn handles(&self) -> impl Iterator<Item = BodyHandle> + '_ {
        self.bodies
            .iter()
            .filter_map(|(i, _)| self.bodies.handle_at(i))
    }

    /// A read-only view of a body.
    pub fn body(&self, h: BodyHandle) -> Result<BodyRef<'_, 'a>, Error> {
        self.bodies.get(h).map(BodyRef).ok_or(Error::StaleHandle)
    }

    fn body_mut(&mut self, h: BodyHandle) -> Result<&mut Body<'a>, Error> {
        self.quiet = false;
        self.bodies.get_mut(h).ok_or(Error::StaleHandle)
    }

    /// Teleport a body (wakes it). Fails on a stale handle or an invalid pose.
    pub fn set_pose(&mut self, h: BodyHandle, pose: Iso) -> Result<(), Error> {
        crate::collide::check_pose(&pose)?;
        self.body_mut(h)?;
        // What rested on it (or under it) must notice: wake the bodies it touched.
        self.wake_touching(h.index);
        let b = self.body_mut(h)?;
        b.place(Iso::new(pose.position, pose.rotation.normalize()));
        b.pose0 = *b.pose();
        b.fat = b.shape.aabb(b.pose());
        b.moved = true;
        b.update_inertia();
        if b.kind != BodyKind::Static {
            wake(b);
        }
        Ok(())
    }

    /// Set the linear velocity of a body's centre of mass (m/s); wakes it. Ignored for
    /// static bodies.
    pub fn set_linear_velocity(&mut self, h: BodyHandle, v: Vec3) -> Result<(), Error> {
        finite_vec(v, Input::LinearVelocity)?;
        let b = self.body_mut(h)?;
        if b.kind != BodyKind::Static {
            b.linear_velocity = v;
            wake(b);
        }
        Ok(())
    }

    /// Set the angular velocity (rad/s, world); wakes the body. Ignored for static bodies.
    pub fn set_angular_velocity(&mut self, h: BodyHandle, w: Vec3) -> Result<(), Error> {
        finite_vec(w, Input::AngularVelocity)?;
        let b = self.body_mut(h)?;
        if b.kind != BodyKind::Static {
            b.angular_velocity = w;
            wake(b);
        }
        Ok(())
    }

    /// Add a force (N) at the centre of mass for the next step; wakes the body. Fails with
    /// `OutOfRange(Force)` if a component of the accumulated force would pass
    /// [`crate::dynamics::snapshot::MAX_STATE_FORCE`] (1e30 N).
    pub fn apply_force(&mut self, h: BodyHandle, f: Vec3) -> Result<(), Error> {
        finite_vec(f, Input::Force)?;
        let b = self.body_mut(h)?;
        if b.is_dynamic() {
            let total = b.force + f;
            if !within_force_bound(total) {
                return Err(Error::OutOfRange(Input::Force));
            }
            b.force = total;
            wake(b);
        }
        Ok(())
    }

    /// Add a torque (N·m, world) for the next step; wakes the body. Fails with
    /// `OutOfRange(Force)` as [`World::apply_force`] does.
    pub fn apply_torque(&mut self, h: BodyHandle, t: Vec3) -> Result<(), Error> {
        finite_vec(t, Input::Force)?;
        let b = self.body_mut(h)?;
        if b.is_dynamic() {
            let total = b.torque + t;
            if !within_force_bound(total) {
                return Err(Error::OutOfRange(Input::Force));
            }
            b.torque = total;
            wake(b);
        }
        Ok(())
    }

    /// Apply an impulse (N·s) at a world point now; wakes the body. Fails with
    /// `OutOfRange(Force)` if the resulting velocity would overflow `f32`.
    pub fn apply_impulse_at(
        &mut self,
        h: BodyHandle,
        impulse: Vec3,
        point: Vec3,
    ) -> Result<(), Error> {
        finite_vec(impulse, Input::Force)?;
        crate::error::position(point)?;
        let b = self.body_mut(h)?;
        if b.is_dynamic() {
            let mut after = *b;
            after.apply_impulse_at(impulse, point);
            if !(after.linear_velocity.is_finite() && after.angular_velocity.is_finite()) {
                return Err(Error::OutOfRange(Input::Force));
            }
            *b = after;
            wake(b);
        }
        Ok(())
    }

    /// Wake a body.
    pub fn wake(&mut self, h: BodyHandle) -> Result<(), Error> {
        let b = self.body_mut(h)?;
        if b.kind != BodyKind::Static {
            wake(b);
        }
        Ok(())
    }

    /// Put a body to sleep now (it wakes when touched by an awake body, or by a setter).
    pub fn sleep(&mut self, h: BodyHandle) -> Result<(), Error> {
        let b = self.body_mut(h)?;
        if b.kind != BodyKind::Static {
            b.awake = false;
            b.linear_velocity = Vec3::ZERO;
            b.angular_velocity = Vec3::ZERO;
        }
        Ok(())
    }

    /// Change a body's material (validated); its contacts combine it from the next step.
    pub fn set_material(&mut self, h: BodyHandle, m: Material) -> Result<(), Error> {
        m.validate()?;
        self.body_mut(h)?.material = m;
        self.recombine_materials(Some(h.index));
        Ok(())
    }

    /// Contacts keep the combined material of their pair: combine it again by the
    /// configured rules, for the contacts of body slot `only` or, with `None`, for all.
    fn recombine_materials(&mut self, only: Option<u32>) {
        let (bodies, cfg) = (&self.bodies, &self.config);
        for c in self.contacts.iter_mut() {
            if only.is_some_and(|i| c.a != i && c.b != i) {
                continue;
            }
            if let (Some(x), Some(y)) = (bodies.at(c.a as usize), bodies.at(c.b as usize)) {
                c.material = cfg.combine_materials(&x.material, &y.material);
            }
        }
    }
}

/// A force or torque a body may carry into a step (and a snapshot may hold).
fn within_force_bound(v: Vec3) -> bool {
    v.is_finite() && v.abs().max_elem() <= crate::dynamics::snapshot::MAX_STATE_FORCE
}

fn wake(b: &mut Body<'_>) {
    b.awake = true;
    b.sleep_time = 0.0;
}

/// A read-only view of a body, from [`World::body`].
#[derive(Clone, Copy, Debug)]
pub struct BodyRef<'w, 'a>(&'w Body<'a>);

impl<'a> BodyRef<'_, 'a> {
    /// Pose of the body frame (m, unit quaternion).
    pub fn pose(&self) -> Iso {
        *self.0.pose()
    }
    /// Position of the body frame's origin (m).
    pub fn position(&self) -> Vec3 {
        self.0.pose().position
    }
    /// Rotation.
    pub fn rotation(&self) -> Quat {
        self.0.pose().rotation
    }
    /// Centre of mass (world, m).
    pub fn center_of_mass(&self) -> Vec3 {
        self.0.world_center()
    }
    /// Linear velocity of the centre of mass (m/s).
    pub fn linear_velocity(&self) -> Vec3 {
        self.0.linear_velocity
    }
    /// Angular velocity (rad/s, world).
    pub fn angular_velocity(&self) -> Vec3 {
        self.0.angular_velocity
    }
    /// Velocity of a world point attached to the body (m/s).
    pub fn velocity_at(&self, p: Vec3) -> Vec3 {
        self.0.velocity_at(p)
    }
    /// Mass (kg); infinite for static and kinematic bodies.
    pub fn mass(&self) -> f32 {
        if self.0.inv_mass > 0.0 {
            1.0 / self.0.inv_mass
        } else {
            f32::INFINITY
        }
    }
    /// Dynamic, static or kinematic.
    pub fn kind(&self) -> BodyKind {
        self.0.kind
    }
    /// The collision shape.
    pub fn shape(&self) -> Shape<'a> {
        self.0.shape
    }
    /// The material.
    pub fn material(&self) -> Material {
        self.0.material
    }
    /// False while the body sleeps.
    pub fn is_awake(&self) -> bool {
        self.0.awake
    }
    /// The user data given at creation.
    pub fn user_data(&self) -> u64 {
        self.0.user_data
    }
    /// Kinetic energy `½ m v² + ½ ωᵀ I ω` (J); 0 for static and kinematic bodies.
    pub fn kinetic_energy(&self) -> f32 {
        let b = self.0;
        if b.inv_mass <= 0.0 {
            return 0.0;
        }
        let lin = 0.5 * b.linear_velocity.length_squared() / b.inv_mass;
        // ωᵀ I ω with I = (I⁻¹)⁻¹ in world axes.
        let ang = match b.inv_inertia_world.inverse() {
            Some(i) => 0.5 * b.angular_velocity.dot(i.mul_vec(b.angular_velocity)),
            None => 0.0,
        };
        lin + ang
    }
}
