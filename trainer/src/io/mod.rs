//! Files in and out: OBJ meshes, joint-angle CSVs, NumPy `.npy` arrays, atomic writes, the
//! check that no output is an input, and where the command line's poses come from.

pub mod angles;
pub mod atomic;
pub mod npy;
pub mod obj;
pub mod outputs;
pub mod source;
