//! Properties: hull.
