//! The UV atlas: which surface point every texel stands for.
