//! Every tunable of the world, with its unit, default and reason.
//!
//! The defaults suit bodies from about 5 cm to 10 m moving up to a few hundred metres per
//! second, in SI units with gravity along −Y (see the README, "Units and conventions").

use crate::error::{finite_vec, non_negative, positive, Error, Input};
use crate::math::Vec3;

/// Allowed penetration (m) that projection and the solver leave in place, so resting
/// contacts stay touching instead of flickering. Box2D uses 0.005 m.
pub const LINEAR_SLOP: f32 = 0.005;

/// Settings of a [`crate::World`]. Build with [`WorldConfig::DEFAULT`] and change fields.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct WorldConfig {
    /// Gravity (m/s²). Default `(0, −9.81, 0)`.
    pub gravity: Vec3,
    /// Fixed time step (s). Default 1/60.
    pub dt: f32,
    /// Sub-steps per step, each of `dt / substeps`. Default 1; 1 to 64.
    pub substeps: u32,
    /// Sequential-impulse velocity iterations per sub-step. Default 8; 1 to 255.
    pub velocity_iterations: u32,
    /// Projection (position) iterations per sub-step. Default 3; 0 to 255.
    pub position_iterations: u32,
    /// Closing speed (m/s) above which restitution applies; slower impacts are
    /// inelastic so resting contacts do not bounce. Default 1.0 m/s (Box2D's value).
    pub restitution_threshold: f32,
    /// Penetration (m) left alone by projection. Default [`LINEAR_SLOP`].
    pub slop: f32,
    /// Fraction of the remaining penetration projection removes per iteration, 0 to 1.
    /// Default 0.2 (Catto's Baumgarte-like factor: fast enough, no overshoot).
    pub projection_factor: f32,
    /// Largest correction (m) projection applies to one contact per iteration.
    /// Default 0.2 m, so deep overlaps separate over several steps instead of exploding.
    pub max_projection: f32,
    /// Speculative margin (m): contact points this far apart are kept, so the solver stops
    /// bodies before they touch. Default 0.02 m (4 × slop).
    pub speculative_margin: f32,
    /// Relative tangential speed (m/s) below which a contact sticks (static friction).
    /// Default 0.01 m/s.
    pub stick_speed: f32,
    /// Linear speed (m/s) below which a body may fall asleep. Default 0.05 m/s.
    pub sleep_linear_speed: f32,
    /// Angular speed (rad/s) below which a body may fall asleep. Default 0.05 rad/s.
    pub sleep_angular_speed: f32,
    /// Time (s) an island must stay slow before it sleeps. Default 0.5 s.
    pub sleep_time: f32,
    /// Whether bodies may sleep at all. Default true; benchmarks switch it off.
    pub sleep_enabled: bool,
    /// Fraction of a body's smallest extent it may move in one step before continuous
    /// collision sweeps it. Default 0.25.
    pub ccd_motion_fraction: f32,
    /// Closing speed (m/s) above which a contact reports a hit event. Default 1.0 m/s.
    pub hit_event_speed: f32,
    /// Largest linear speed (m/s) a body may reach; faster is clamped. Default 1000 m/s.
    pub max_linear_speed: f32,
    /// Largest angular speed (rad/s) a body may reach. Default 100 rad/s.
    pub max_angular_speed: f32,
}

impl WorldConfig {
    /// The defaults listed on each field.
    pub const DEFAULT: WorldConfig = WorldConfig {
        gravity: Vec3::new(0.0, -9.81, 0.0),
        dt: 1.0 / 60.0,
        substeps: 1,
        velocity_iterations: 8,
        position_iterations: 3,
        restitution_threshold: 1.0,
        slop: LINEAR_SLOP,
        projection_factor: 0.2,
        max_projection: 0.2,
        speculative_margin: 4.0 * LINEAR_SLOP,
        stick_speed: 0.01,
        sleep_linear_speed: 0.05,
        sleep_angular_speed: 0.05,
        sleep_time: 0.5,
        sleep_enabled: true,
        ccd_motion_fraction: 0.25,
        hit_event_speed: 1.0,
        max_linear_speed: 1000.0,
        max_angular_speed: 100.0,
    };

    /// Check every field; the error names the first bad one.
    pub fn validate(&self) -> Result<(), Error> {
        finite_vec(self.gravity, Input::Gravity)?;
        positive(self.dt, Input::Time)?;
        if self.substeps == 0 || self.substeps > 64 {
            return Err(Error::OutOfRange(Input::Iterations));
        }
        if self.velocity_iterations == 0 || self.velocity_iterations > 255 {
            return Err(Error::OutOfRange(Input::Iterations));
        }
        if self.position_iterations > 255 {
            return Err(Error::OutOfRange(Input::Iterations));
        }
        non_negative(self.restitution_threshold, Input::Config)?;
        non_negative(self.slop, Input::Distance)?;
        non_negative(self.projection_factor, Input::Config)?;
        if self.projection_factor > 1.0 {
            return Err(Error::OutOfRange(Input::Config));
        }
        non_negative(self.max_projection, Input::Distance)?;
        non_negative(self.speculative_margin, Input::Distance)?;
        non_negative(self.stick_speed, Input::Config)?;
        non_negative(self.sleep_linear_speed, Input::Config)?;
        non_negative(self.sleep_angular_speed, Input::Config)?;
        non_negative(self.sleep_time, Input::Time)?;
        positive(self.ccd_motion_fraction, Input::Config)?;
        non_negative(self.hit_event_speed, Input::Config)?;
        positive(self.max_linear_speed, Input::Config)?;
        positive(self.max_angular_speed, Input::Config)?;
        Ok(())
    }
}

impl Default for WorldConfig {
    fn default() -> Self {
        WorldConfig::DEFAULT
    }
}
