//! Properties: contact manifolds.
