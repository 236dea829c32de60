//! Properties: narrow.
