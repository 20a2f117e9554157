//! Encoding and compressing a sequence of SH light maps.
