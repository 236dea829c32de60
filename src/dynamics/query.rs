//! World queries: ray casts and shape overlap, filtered by group and mask.
