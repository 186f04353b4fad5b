//! 2.5D contour machining of planar profiles with B-spline wavelets (DESIGN.md §3.9; seed 004
//! ch. 3–4). So far: the endpoint-interpolating cubic B-spline wavelet filters ([`wavelet`]).

pub mod wavelet;
