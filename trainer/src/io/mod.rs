//! Files in and out: OBJ meshes, joint-angle CSVs, NumPy `.npy` arrays, atomic writes, and
//! where the command line's poses come from.

pub mod angles;
pub mod atomic;
pub mod npy;
pub mod obj;
pub mod source;
