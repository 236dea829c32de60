//! Polygon clipping for face contacts (Sutherland–Hodgman against the side planes of a
//! reference face) and reduction of the clipped points to at most 4.
