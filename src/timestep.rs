//! A fixed-timestep accumulator: turns variable frame times into a whole number of fixed
//! steps, plus an interpolation factor for rendering between the last two states.
//!
//! A [`World`](crate::World) always advances by its fixed `dt`. A game's frames do not
//! last `dt`: one frame is 7 ms, the next 19 ms. [`FixedTimestep`] carries the time left
//! over from frame to frame and says how many steps each frame should run (Glenn
//! Fiedler, "Fix your timestep!", 2004). Two safeguards come with it:
//!
//! - **A cap on steps per frame.** A frame that took too long (a debugger break, a
//!   loading hitch, a slow machine) would ask for more steps than can be run in a frame,
//!   making the next frame slower still: the "spiral of death". At most `max_steps` are
//!   run; the steps beyond are dropped (the simulation runs slower than the wall clock
//!   for that frame) and counted in [`FrameSteps::dropped`], so you can see it happen.
//! - **An interpolation factor** [`FrameSteps::alpha`] in `[0, 1)`: how far the wall clock is
//!   between the last step and the next one. Draw `previous.lerp(current, alpha)` and the
//!   motion stays smooth at any frame rate (it is drawn at most one step late).
//!
//! ```
//! use carom::{FixedTimestep, World};
//!
//! # fn main() -> Result<(), carom::Error> {
//! let mut world: World<'static, 8, 16> = World::new();
//! let mut clock = FixedTimestep::new(world.config().dt, 4)?; // dt = 1/60 s
//! // A 40 ms frame runs two steps of 16.7 ms and carries 6.7 ms to the next frame.
//! let s = clock.advance(0.040)?;
//! assert_eq!((s.steps, s.dropped), (2, 0));
//! for _ in 0..s.steps {
//!     world.step();
//! }
//! assert!((s.alpha - 0.4).abs() < 1e-4); // 6.7 ms is 0.4 of a step
//! # Ok(())
//! # }
//! ```
//!
//! The accumulator is not part of the world's state: it lives outside it, so it is in no
//! snapshot or checksum, and rollback code keeps it apart from the world (it counts the
//! local player's wall clock, not simulation time).
//!
//! # Precision
//!
//! The accumulator is an `f64` of seconds, and `dt` is an `f32` (the world's step). The
//! only rounding is the addition of each frame's time to the accumulator: taking a step
//! off (subtracting `dt`) is exact while the accumulator holds fewer than `2²⁹` steps
//! (always, unless steps are dropped: `max_steps` is at most
//! [`FixedTimestep::MAX_STEPS`] = `2¹⁶`), and dropping steps keeps the exact remainder of
//! a step. So each call to [`FixedTimestep::advance`] moves the simulated clock away from the sum
//! of the frame times by at most half an `f64` ulp of `accumulator + elapsed`, below
//! `1.2 · 10⁻¹⁶ · (dt + elapsed)` seconds: a million frames of 1/60 s drift by less than
//! `4 · 10⁻¹² s`, far from a step. A step is run when the accumulated time reaches `dt`
//! exactly (`>=`), so frames of exactly `dt` run exactly one step each.

use crate::error::{Error, Input};

/// A fixed-timestep accumulator with a cap on steps per frame. See the
/// [module docs](crate::timestep).
///
/// ```
/// use carom::FixedTimestep;
///
/// # fn main() -> Result<(), carom::Error> {
/// let mut clock = FixedTimestep::new(1.0 / 64.0, 5)?;
/// let s = clock.advance(1.0)?; // a one-second hitch: 64 steps due
/// assert_eq!((s.steps, s.dropped), (5, 59)); // run 5, drop 59
/// assert_eq!(s.alpha, 0.0);
/// # Ok(())
/// # }
/// ```
// No serde: a deserialised clock would bypass `new`'s checks (a negative `dt` or a huge
// `max_steps` would make `advance` loop for a long time).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct FixedTimestep {
    /// The fixed step (s), as `f64` (exact: it was an `f32`).
    dt: f64,
    /// The cap on steps per call of `advance`.
    max_steps: u32,
    /// Time carried over (s), in `[0, dt)` between calls.
    accumulator: f64,
}

/// What one frame should do: run [`FrameSteps::steps`] fixed steps, then draw with
/// [`FrameSteps::alpha`]. Returned by [`FixedTimestep::advance`].
///
/// ```
/// use carom::FixedTimestep;
///
/// # fn main() -> Result<(), carom::Error> {
/// let mut clock = FixedTimestep::new(0.25, 8)?; // dyadic times: exact arithmetic
/// let s = clock.advance(0.625)?;
/// assert_eq!((s.steps, s.dropped, s.alpha), (2, 0, 0.5));
/// # Ok(())
/// # }
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct FrameSteps {
    /// Fixed steps to run now, at most the clock's `max_steps`.
    pub steps: u32,
    /// FrameSteps that were due but dropped by the cap (the simulation fell behind the wall
    /// clock by `dropped · dt`). Saturates at `u64::MAX` for absurd frame times.
    pub dropped: u64,
    /// Interpolation factor in `[0, 1)`: the fraction of a step the wall clock is past
    /// the last step. Draw `previous + (current − previous) · alpha`.
    pub alpha: f32,
}

impl FixedTimestep {
    /// The largest cap on steps per frame [`FixedTimestep::new`] accepts (65 536): it
    /// bounds the work of one [`FixedTimestep::advance`].
    pub const MAX_STEPS: u32 = 1 << 16;

    /// A clock for steps of `dt` seconds (normally `world.config().dt`) that runs at most
    /// `max_steps` steps per frame, with nothing accumulated.
    ///
    /// Fails with `NonFinite(Time)` or `NotPositive(Time)` for a bad `dt`,
    /// `NotPositive(Iterations)` for `max_steps == 0` and `OutOfRange(Iterations)` above
    /// [`FixedTimestep::MAX_STEPS`].
    ///
    /// ```
    /// use carom::{Error, FixedTimestep, Input};
    ///
    /// assert!(FixedTimestep::new(1.0 / 60.0, 4).is_ok());
    /// assert_eq!(FixedTimestep::new(0.0, 4), Err(Error::NotPositive(Input::Time)));
    /// assert_eq!(FixedTimestep::new(1.0 / 60.0, 0), Err(Error::NotPositive(Input::Iterations)));
    /// ```
    pub fn new(dt: f32, max_steps: u32) -> Result<FixedTimestep, Error> {
        let dt = crate::error::positive(dt, Input::Time)?;
        if max_steps == 0 {
            return Err(Error::NotPositive(Input::Iterations));
        }
        if max_steps > Self::MAX_STEPS {
            return Err(Error::OutOfRange(Input::Iterations));
        }
        Ok(FixedTimestep {
            dt: f64::from(dt),
            max_steps,
            accumulator: 0.0,
        })
    }

    /// The fixed step (s).
    ///
    /// ```
    /// # fn main() -> Result<(), carom::Error> {
    /// let clock = carom::FixedTimestep::new(0.01, 3)?;
    /// assert_eq!(clock.dt(), 0.01);
    /// # Ok(())
    /// # }
    /// ```
    pub fn dt(&self) -> f32 {
        // Exact: `dt` was an f32.
        self.dt as f32
    }

    /// The cap on steps per frame.
    ///
    /// ```
    /// # fn main() -> Result<(), carom::Error> {
    /// let clock = carom::FixedTimestep::new(0.01, 3)?;
    /// assert_eq!(clock.max_steps(), 3);
    /// # Ok(())
    /// # }
    /// ```
    pub fn max_steps(&self) -> u32 {
        self.max_steps
    }

    /// The time carried over to the next frame (s), in `[0, dt)`.
    ///
    /// ```
    /// # fn main() -> Result<(), carom::Error> {
    /// let mut clock = carom::FixedTimestep::new(0.5, 3)?;
    /// clock.advance(1.25)?;
    /// assert_eq!(clock.accumulator(), 0.25);
    /// # Ok(())
    /// # }
    /// ```
    pub fn accumulator(&self) -> f64 {
        self.accumulator
    }

    /// The interpolation factor of the time carried over, in `[0, 1)` (the last
    /// [`FrameSteps::alpha`]).
    ///
    /// ```
    /// # fn main() -> Result<(), carom::Error> {
    /// let mut clock = carom::FixedTimestep::new(0.5, 3)?;
    /// clock.advance(0.125)?;
    /// assert_eq!(clock.alpha(), 0.25);
    /// # Ok(())
    /// # }
    /// ```
    pub fn alpha(&self) -> f32 {
        let a = (self.accumulator / self.dt) as f32;
        // The division or the narrowing can round a remainder just below `dt` up to 1.
        if a < 1.0 {
            a
        } else {
            ALPHA_MAX
        }
    }

    /// Forget the time carried over (after a pause or a restore, say).
    ///
    /// ```
    /// # fn main() -> Result<(), carom::Error> {
    /// let mut clock = carom::FixedTimestep::new(0.5, 3)?;
    /// clock.advance(0.25)?;
    /// clock.reset();
    /// assert_eq!(clock.accumulator(), 0.0);
    /// # Ok(())
    /// # }
    /// ```
    pub fn reset(&mut self) {
        self.accumulator = 0.0;
    }

    /// Add a frame's `elapsed` wall-clock time (s) and say how many fixed steps to run
    /// now, how many were dropped by the cap, and the interpolation factor.
    ///
    /// When more than `max_steps` steps are due, `max_steps` are returned, the rest are
    /// counted in [`FrameSteps::dropped`] and forgotten, and the fraction of a step left over
    /// is kept. Zero elapsed time is fine (no step, the same alpha).
    ///
    /// Fails, changing nothing, with `NonFinite(Time)` for a NaN or infinite `elapsed`
    /// and `Negative(Time)` for a negative one (a clock that went backwards: pass 0).
    ///
    /// ```
    /// use carom::{Error, FixedTimestep, Input};
    ///
    /// # fn main() -> Result<(), carom::Error> {
    /// let mut clock = FixedTimestep::new(0.5, 3)?;
    /// assert_eq!(clock.advance(0.75)?.steps, 1);
    /// assert_eq!(clock.advance(0.25)?.steps, 1); // 0.25 carried + 0.25
    /// assert_eq!(clock.advance(-1.0), Err(Error::Negative(Input::Time)));
    /// assert_eq!(clock.advance(f64::NAN), Err(Error::NonFinite(Input::Time)));
    /// # Ok(())
    /// # }
    /// ```
    pub fn advance(&mut self, elapsed: f64) -> Result<FrameSteps, Error> {
        if !elapsed.is_finite() {
            return Err(Error::NonFinite(Input::Time));
        }
        if elapsed < 0.0 {
            return Err(Error::Negative(Input::Time));
        }
        // `elapsed + 0.0` turns a −0 into +0 (−0 passes the check above).
        let mut acc = self.accumulator + elapsed + 0.0;
        let mut steps: u32 = 0;
        // Exact subtractions (module docs, Precision); at most `max_steps` of them.
        while acc >= self.dt && steps < self.max_steps {
            acc -= self.dt;
            steps += 1;
        }
        let mut dropped: u64 = 0;
        if acc >= self.dt {
            // Over the cap: keep the exact remainder of a step (`%` on floats is exact),
            // count the whole steps in between. `as u64` saturates.
            let rem = acc % self.dt;
            dropped = ((acc - rem) / self.dt + 0.5) as u64;
            acc = rem;
        }
        // Defensive: `acc` is finite and in [0, dt) here whatever the input.
        self.accumulator = if acc >= 0.0 && acc < self.dt {
            acc
        } else {
            0.0
        };
        Ok(FrameSteps {
            steps,
            dropped,
            alpha: self.alpha(),
        })
    }
}

/// The largest `f32` below 1: where alpha is clamped when rounding reaches 1.
const ALPHA_MAX: f32 = 1.0 - f32::EPSILON / 2.0;

#[cfg(test)]
mod tests {
    use super::*;

    fn clock(dt: f32, max: u32) -> FixedTimestep {
        FixedTimestep::new(dt, max).unwrap()
    }

    #[test]
    fn rejects_bad_construction() {
        assert_eq!(
            FixedTimestep::new(f32::NAN, 1),
            Err(Error::NonFinite(Input::Time))
        );
        assert_eq!(
            FixedTimestep::new(f32::INFINITY, 1),
            Err(Error::NonFinite(Input::Time))
        );
        assert_eq!(
            FixedTimestep::new(-0.1, 1),
            Err(Error::NotPositive(Input::Time))
        );
        assert_eq!(
            FixedTimestep::new(0.0, 1),
            Err(Error::NotPositive(Input::Time))
        );
        assert_eq!(
            FixedTimestep::new(0.1, 0),
            Err(Error::NotPositive(Input::Iterations))
        );
        assert_eq!(
            FixedTimestep::new(0.1, FixedTimestep::MAX_STEPS + 1),
            Err(Error::OutOfRange(Input::Iterations))
        );
        // The smallest positive dt and the largest cap are accepted.
        assert!(FixedTimestep::new(f32::from_bits(1), 1).is_ok());
        let mut most = clock(f32::from_bits(1), FixedTimestep::MAX_STEPS);
        let s = most.advance(f64::MAX).unwrap();
        assert_eq!((s.steps, s.dropped), (FixedTimestep::MAX_STEPS, u64::MAX));
    }

    #[test]
    fn rejects_bad_elapsed_and_changes_nothing() {
        let mut c = clock(0.5, 4);
        c.advance(0.25).unwrap();
        let before = c;
        for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            assert_eq!(c.advance(bad), Err(Error::NonFinite(Input::Time)));
        }
        for bad in [-1e-300, -0.25, -1e300, f64::MIN] {
            assert_eq!(c.advance(bad), Err(Error::Negative(Input::Time)));
        }
        assert_eq!(c, before);
    }

    #[test]
    fn zero_and_negative_zero_frames() {
        let mut c = clock(0.5, 4);
        assert_eq!(
            c.advance(0.0).unwrap(),
            FrameSteps {
                steps: 0,
                dropped: 0,
                alpha: 0.0
            }
        );
        let s = c.advance(-0.0).unwrap();
        assert_eq!((s.steps, s.dropped), (0, 0));
        assert_eq!(s.alpha.to_bits(), 0.0f32.to_bits(), "no negative zero");
        c.advance(0.125).unwrap();
        assert_eq!(c.advance(0.0).unwrap().alpha, 0.25, "zero keeps alpha");
    }

    #[test]
    fn exact_counts_and_alpha_with_dyadic_times() {
        // dt = 0.25 and frame times that are multiples of 1/64: every value is exact.
        let mut c = clock(0.25, 8);
        let cases: [(f64, u32, f32); 7] = [
            (0.0625, 0, 0.25),     // carried 0.0625
            (0.125, 0, 0.75),      // carried 0.1875
            (0.0625, 1, 0.0),      // 0.25: exactly one step, nothing left
            (0.25, 1, 0.0),        // exactly dt: one step
            (0.6875, 2, 0.75),     // 2.75 steps
            (0.3125, 2, 0.0),      // 0.1875 + 0.3125 = 0.5: two steps
            (0.015625, 0, 0.0625), // carried 1/64
        ];
        for (i, (elapsed, steps, alpha)) in cases.into_iter().enumerate() {
            let s = c.advance(elapsed).unwrap();
            assert_eq!(
                s,
                FrameSteps {
                    steps,
                    dropped: 0,
                    alpha
                },
                "frame {i}"
            );
        }
    }

    #[test]
    fn frames_of_exactly_dt_run_one_step_each() {
        let dt = 1.0f32 / 60.0;
        let mut c = clock(dt, 4);
        for _ in 0..100_000 {
            let s = c.advance(f64::from(dt)).unwrap();
            assert_eq!(
                s,
                FrameSteps {
                    steps: 1,
                    dropped: 0,
                    alpha: 0.0
                }
            );
        }
        assert_eq!(c.accumulator(), 0.0);
    }

    #[test]
    fn the_cap_drops_whole_steps_and_keeps_the_fraction() {
        let mut c = clock(0.25, 3);
        // 10.5 steps due: 3 run, 7 dropped, half a step kept.
        let s = c.advance(2.625).unwrap();
        assert_eq!(
            s,
            FrameSteps {
                steps: 3,
                dropped: 7,
                alpha: 0.5
            }
        );
        assert_eq!(c.accumulator(), 0.125);
        // Exactly at the cap: nothing dropped.
        let s = c.advance(0.625).unwrap(); // 0.125 + 0.625 = 0.75 = 3 steps
        assert_eq!(
            s,
            FrameSteps {
                steps: 3,
                dropped: 0,
                alpha: 0.0
            }
        );
        // One over the cap: one dropped.
        let s = c.advance(1.0).unwrap();
        assert_eq!(
            s,
            FrameSteps {
                steps: 3,
                dropped: 1,
                alpha: 0.0
            }
        );
        // A cap of one.
        let mut one = clock(0.25, 1);
        let s = one.advance(0.8125).unwrap(); // 3.25 steps
        assert_eq!(
            s,
            FrameSteps {
                steps: 1,
                dropped: 2,
                alpha: 0.25
            }
        );
    }

    #[test]
    fn huge_frames_saturate_without_panicking() {
        let mut c = clock(1.0 / 60.0, 5);
        let s = c.advance(1.0e300).unwrap();
        assert_eq!(s.steps, 5);
        assert_eq!(s.dropped, u64::MAX, "saturates");
        assert!((0.0..1.0).contains(&s.alpha));
        assert!(c.accumulator() >= 0.0 && c.accumulator() < f64::from(c.dt()));
        let s = c.advance(f64::MAX).unwrap();
        assert_eq!((s.steps, s.dropped), (5, u64::MAX));
        assert!((0.0..1.0).contains(&s.alpha));
        // A one-hour hitch at 60 Hz: 216000 steps due, 5 run.
        let mut c = clock(0.25, 5);
        let s = c.advance(3600.0).unwrap();
        assert_eq!(
            s,
            FrameSteps {
                steps: 5,
                dropped: 14_395,
                alpha: 0.0
            }
        );
        // The smallest dt with a large frame: still bounded work.
        let mut tiny = clock(f32::from_bits(1), 2);
        let s = tiny.advance(1.0).unwrap();
        assert_eq!(s.steps, 2);
        assert!(s.dropped > 1 << 60);
        assert!((0.0..1.0).contains(&s.alpha));
    }

    #[test]
    fn alpha_stays_below_one() {
        let mut c = clock(1.0 / 60.0, 4);
        // Just below dt: alpha rounds to 1 in f32 and is clamped.
        let just_below = f64::from(1.0f32 / 60.0) * (1.0 - 1e-12);
        let s = c.advance(just_below).unwrap();
        assert_eq!(s.steps, 0);
        assert_eq!(s.alpha, ALPHA_MAX);
        assert!(s.alpha < 1.0);
        let mut rng = crate::rng::SplitMix64::new(7);
        for _ in 0..100_000 {
            let s = c.advance(f64::from(rng.range(0.0, 0.05))).unwrap();
            assert!((0.0..1.0).contains(&s.alpha), "{s:?}");
            assert!(s.steps <= 4);
        }
    }

    /// `2^k` as an f64 (exact).
    fn pow2(k: u32) -> f64 {
        (1u128 << k) as f64
    }

    /// `x · 2^shift` as an integer: the exact value of a non-negative `x` with no bits
    /// below `2^-shift`, in fixed point.
    fn fixed(x: f64, shift: u32) -> u128 {
        let scaled = x * pow2(shift);
        assert_eq!(scaled, (scaled as u128) as f64, "not exact at this shift");
        scaled as u128
    }

    #[test]
    fn many_frames_drift_within_the_documented_bound() {
        // A million frames of 1/144 s (f64) with dt = 1/60 s (f32): no frame time or sum
        // is exact, and one frame in twelve ends within rounding of a step boundary.
        let dt = 1.0f32 / 60.0;
        let frame = 1.0f64 / 144.0;
        let n: u64 = 1_000_000;
        let mut c = clock(dt, 4);
        let mut steps: u64 = 0;
        for _ in 0..n {
            let s = c.advance(frame).unwrap();
            assert_eq!(s.dropped, 0);
            steps += u64::from(s.steps);
        }
        // Exact arithmetic in units of 2^-80 s: frame and dt are exact there.
        let unit = 80;
        let total = fixed(frame, unit) * u128::from(n);
        let dt_fixed = fixed(f64::from(dt), unit);
        let exact_steps = (total / dt_fixed) as u64;
        let exact_rem = total % dt_fixed;
        // The simulated clock: steps · dt + accumulator, against the exact total.
        let simulated = u128::from(steps) * dt_fixed + fixed(c.accumulator(), unit);
        let drift = simulated.abs_diff(total) as f64 / pow2(unit);
        // Documented bound: half an ulp of (acc + elapsed) < dt + elapsed per call.
        let bound = n as f64 * 1.2e-16 * (f64::from(dt) + frame);
        assert!(drift <= bound, "drift {drift:e} s > bound {bound:e} s");
        assert!(drift < 4e-12, "a million frames: {drift:e} s");
        // The step count is exact unless the exact remainder is within the drift of a
        // step boundary.
        let near = (exact_rem as f64 / pow2(unit)) < drift
            || ((dt_fixed - exact_rem) as f64 / pow2(unit)) < drift;
        if near {
            assert!(steps.abs_diff(exact_steps) <= 1);
        } else {
            assert_eq!(steps, exact_steps);
        }
        assert_eq!(exact_steps, 416_666);
    }
}
