//! Hand-written CPU rasterizer of sightline: perspective views (cube faces or any
//! frustum), near-plane clipping, depth and object-id buffers, three coverage rules
//! (standard, inner/under-estimating, outer/over-estimating), conservative depth and a
//! hierarchical max-depth pyramid.
