//! Prints every `.shlm` codec variant's bytes, ratio, error and decode time on the synthetic
//! 128², order-4, 40-frame clip of `lightmap::codec::synth` (the clip the codec's tests use and
//! the sign-mode table of `lightmap/codec/shared_exp.rs` was measured on), then the default's:
//!
//! `cargo run -p aprt-trainer --release --example shlm_codecs`

use aprt_trainer::lightmap::codec::synth::clip;
use aprt_trainer::lightmap::codec::{CodecSettings, ShlmFile, compare, encode};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let seq = clip(128, 4, 40, 1e-3);
    println!(
        "{:<34} {:>10} {:>8} {:>9} {:>10} {:>9}",
        "variant", "bytes", "ratio", "rel err", "max abs", "ms/frame"
    );
    for r in compare(&seq) {
        println!(
            "{:<34} {:>10} {:>8.1} {:>8.3}% {:>10.2e} {:>9.3}",
            r.name,
            r.bytes,
            r.ratio,
            100.0 * r.relative_error,
            r.max_abs_error,
            r.decode_ms_per_frame
        );
    }
    let bytes = encode(&seq, &CodecSettings::default())?;
    println!("default: {}", ShlmFile::parse(&bytes)?.describe());
    Ok(())
}
