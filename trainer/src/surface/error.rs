//! Error in the units users read, summed over frames: the relative transfer error
//! `‖pred − truth‖ / ‖truth‖` of the pose-driven paper (section 6) and the RMS shading error
//! in 8-bit grey levels under a lighting, each point weighted by the area it stands for (1 at
//! the vertices, where every vertex counts alike).

use crate::lighting::GREY_PER_IRRADIANCE;

/// What an [`ErrorSum`] measured.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct Accuracy {
    /// `‖pred − truth‖ / ‖truth‖` over every frame, point and coefficient of the truth (the
    /// bands a prediction leaves out count as error).
    pub transfer_error: f64,
    /// RMS shading error, grey levels.
    pub grey_rms: f64,
    /// Largest shading error, grey levels.
    pub grey_max: f64,
}

/// Running sums of a prediction's error against the truth, frame by frame.
pub struct ErrorSum<'a> {
    /// Luminance SH lighting, as many coefficients as the truth has.
    lighting: &'a [f32],
    diff: f64,
    norm: f64,
    grey2: f64,
    grey_max: f64,
    weight: f64,
}

impl<'a> ErrorSum<'a> {
    /// Sums under `lighting` (luminance SH, one value per coefficient of the truth).
    pub fn new(lighting: &'a [f32]) -> Self {
        ErrorSum {
            lighting,
            diff: 0.0,
            norm: 0.0,
            grey2: 0.0,
            grey_max: 0.0,
            weight: 0.0,
        }
    }

    /// Adds one frame: `pred` holds `pred_n2` values per point, `truth` the lighting's count
    /// per point, `weights` one per point (`None`: every point 1). A prediction of fewer
    /// coefficients than the truth shades with its own and misses the rest.
    pub fn add(&mut self, pred: &[f32], pred_n2: usize, truth: &[f32], weights: Option<&[f64]>) {
        let n2 = self.lighting.len();
        let points = truth.len() / n2.max(1);
        for j in 0..points {
            let w = weights.map_or(1.0, |w| w[j]);
            let p = &pred[j * pred_n2..][..pred_n2];
            let t = &truth[j * n2..][..n2];
            let (mut shade, mut exact, mut diff, mut norm) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
            for (c, (&tc, &l)) in t.iter().zip(self.lighting).enumerate() {
                let (tc, l) = (f64::from(tc), f64::from(l));
                let pc = p.get(c).map_or(0.0, |&x| f64::from(x));
                diff += (pc - tc).powi(2);
                norm += tc * tc;
                exact += l * tc;
                if c < pred_n2 {
                    shade += l * pc;
                }
            }
            let grey = (shade - exact).abs() * GREY_PER_IRRADIANCE;
            self.diff += w * diff;
            self.norm += w * norm;
            self.grey2 += w * grey * grey;
            self.grey_max = self.grey_max.max(grey);
            self.weight += w;
        }
    }

    /// The sums' figures.
    pub fn finish(&self) -> Accuracy {
        Accuracy {
            transfer_error: (self.diff / self.norm.max(f64::MIN_POSITIVE)).sqrt(),
            grey_rms: (self.grey2 / self.weight.max(f64::MIN_POSITIVE)).sqrt(),
            grey_max: self.grey_max,
        }
    }
}
