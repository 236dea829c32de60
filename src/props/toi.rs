//! Properties: toi.
