//! Property checks shared by the test-suite (on stable, with seeded inputs) and the fuzz
//! targets (with arbitrary inputs). Each function takes plain inputs, runs a query and
//! returns `Err(Violation)` naming the first property that failed. None of them panics.

mod hull;
mod manifold;
mod narrow;
mod toi;
mod world;

pub use hull::*;
pub use manifold::*;
pub use narrow::*;
pub use toi::*;
pub use world::*;

/// A broken property: which one, as a static message.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Violation(pub &'static str);

/// `Ok(())` when `cond` holds, else the violation `what`.
#[inline]
pub fn check(cond: bool, what: &'static str) -> Result<(), Violation> {
    if cond {
        Ok(())
    } else {
        Err(Violation(what))
    }
}
