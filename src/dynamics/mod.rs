//! Stateful simulation: bodies in pools, the stages of the step, queries.

pub(crate) mod aabb_tree;
pub mod body;
pub(crate) mod broad_phase;
pub(crate) mod ccd;
pub(crate) mod contact;
pub(crate) mod contact_solver;
pub mod events;
pub(crate) mod mid_phase;
pub(crate) mod pool;
pub(crate) mod projection;
pub mod query;
pub(crate) mod sleep;
pub mod snapshot;
pub(crate) mod solver;
pub(crate) mod support;
pub(crate) mod union_find;
pub(crate) mod wide;

pub use pool::BodyHandle;
