//! The paper's static two-layer network: `y = LW · tanh(IW · x + b1) + b2`, with inputs and
//! targets scaled to [-1, 1] as MATLAB's `mapminmax` does.

use nalgebra::{DMatrix, DVector};
use rand::Rng;
use serde::{Deserialize, Serialize};

/// Per-row linear map of a range [min, max] onto [-1, 1] (`mapminmax`). A row whose min
/// equals its max (a constant input) passes through unchanged.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MinMaxScaling {
    /// Smallest value of each row in the data the scaling was fitted to.
    pub min: Vec<f64>,
    /// Largest value of each row.
    pub max: Vec<f64>,
}

impl MinMaxScaling {
    /// Fits to `data`, one row per variable, one column per sample.
    pub fn fit(data: &DMatrix<f64>) -> Self {
        let rows = 0..data.nrows();
        Self { min: rows.clone().map(|r| data.row(r).min()).collect(), max: rows.map(|r| data.row(r).max()).collect() }
    }

    /// Gain and offset of row `r`: scaled = gain · (x − min) − 1, or x if the row is constant.
    #[inline]
    fn gain(&self, r: usize) -> Option<f64> {
        let span = self.max[r] - self.min[r];
        (span > 0.0).then(|| 2.0 / span)
    }

    /// Scales one value of row `r`.
    #[inline]
    pub fn apply(&self, r: usize, x: f64) -> f64 {
        match self.gain(r) {
            Some(g) => g * (x - self.min[r]) - 1.0,
            None => x,
        }
    }

    /// Undoes [`MinMaxScaling::apply`] for one value of row `r`.
    #[inline]
    pub fn reverse(&self, r: usize, y: f64) -> f64 {
        match self.gain(r) {
            Some(g) => (y + 1.0) / g + self.min[r],
            None => y,
        }
    }

    /// Scales every column of `data`.
    pub fn apply_all(&self, data: &DMatrix<f64>) -> DMatrix<f64> {
        DMatrix::from_fn(data.nrows(), data.ncols(), |r, c| self.apply(r, data[(r, c)]))
    }

    /// Factor by which row `r`'s squared errors grow when unscaled: (span / 2)².
    pub fn error_scale(&self, r: usize) -> f64 {
        self.gain(r).map_or(1.0, |g| 1.0 / (g * g))
    }
}

/// A two-layer feed-forward network: tansig hidden layer, linear output layer.
/// (Stored on disk through [`crate::WeightsFile`].)
#[derive(Clone, Debug, PartialEq)]
pub struct Mlp {
    /// Input weights, hidden × inputs.
    pub iw: DMatrix<f64>,
    /// Hidden biases.
    pub b1: DVector<f64>,
    /// Layer weights, outputs × hidden.
    pub lw: DMatrix<f64>,
    /// Output biases.
    pub b2: DVector<f64>,
    /// Scaling of the inputs.
    pub input_scaling: MinMaxScaling,
    /// Scaling of the outputs (targets).
    pub output_scaling: MinMaxScaling,
}

impl Mlp {
    /// A network of the given sizes with Nguyen–Widrow hidden weights and uniform [-1, 1]
    /// output weights drawn from `rng`, and the given scalings.
    pub fn nguyen_widrow(hidden: usize, input_scaling: MinMaxScaling, output_scaling: MinMaxScaling, rng: &mut impl Rng) -> Self {
        let (n_in, n_out) = (input_scaling.min.len(), output_scaling.min.len());
        // Nguyen–Widrow: rows of random direction and length 0.7·H^(1/N); biases spread
        // evenly over [-len, len] so the hidden units' active regions tile the scaled input box.
        let magnitude = 0.7 * (hidden as f64).powf(1.0 / n_in as f64);
        let mut iw: DMatrix<f64> = DMatrix::from_fn(hidden, n_in, |_, _| rng.gen_range(-1.0..1.0));
        for mut row in iw.row_iter_mut() {
            let norm = row.norm();
            if norm > 0.0 {
                row *= magnitude / norm;
            }
        }
        let b1 = DVector::from_fn(hidden, |j, _| {
            if hidden == 1 {
                0.0
            } else {
                let spread = -1.0 + 2.0 * j as f64 / (hidden - 1) as f64;
                magnitude * spread * iw[(j, 0)].signum()
            }
        });
        let lw = DMatrix::from_fn(n_out, hidden, |_, _| rng.gen_range(-1.0..1.0));
        let b2 = DVector::from_fn(n_out, |_, _| rng.gen_range(-1.0..1.0));
        Self { iw, b1, lw, b2, input_scaling, output_scaling }
    }

    /// Number of inputs.
    pub fn inputs(&self) -> usize {
        self.iw.ncols()
    }
    /// Number of hidden neurons.
    pub fn hidden(&self) -> usize {
        self.iw.nrows()
    }
    /// Number of outputs.
    pub fn outputs(&self) -> usize {
        self.lw.nrows()
    }

    /// Number of trainable parameters: H(N + 1) + K(H + 1).
    pub fn parameter_count(&self) -> usize {
        self.hidden() * (self.inputs() + 1) + self.outputs() * (self.hidden() + 1)
    }

    /// Evaluates the network on one sample (original units) into `out`, using `hidden`
    /// (length H) as scratch; allocates nothing.
    pub fn evaluate_into(&self, x: &[f64], hidden: &mut [f64], out: &mut [f64]) {
        let (n, h) = (self.inputs(), self.hidden());
        for j in 0..h {
            let mut s = self.b1[j];
            for i in 0..n {
                s += self.iw[(j, i)] * self.input_scaling.apply(i, x[i]);
            }
            hidden[j] = s.tanh();
        }
        for (k, o) in out.iter_mut().enumerate() {
            let mut s = self.b2[k];
            for j in 0..h {
                s += self.lw[(k, j)] * hidden[j];
            }
            *o = self.output_scaling.reverse(k, s);
        }
    }

    /// Evaluates the network on one sample (original units).
    pub fn evaluate(&self, x: &[f64]) -> Vec<f64> {
        let mut hidden = vec![0.0; self.hidden()];
        let mut out = vec![0.0; self.outputs()];
        self.evaluate_into(x, &mut hidden, &mut out);
        out
    }

    /// The parameters as one vector: for each hidden neuron j its input weights then its bias,
    /// then for each output k its layer weights then its bias.
    pub fn parameters(&self) -> Vec<f64> {
        let mut p = Vec::with_capacity(self.parameter_count());
        for j in 0..self.hidden() {
            p.extend(self.iw.row(j).iter());
            p.push(self.b1[j]);
        }
        for k in 0..self.outputs() {
            p.extend(self.lw.row(k).iter());
            p.push(self.b2[k]);
        }
        p
    }

    /// Sets the parameters from a vector ordered as [`Mlp::parameters`].
    pub fn set_parameters(&mut self, p: &[f64]) {
        let (n, h) = (self.inputs(), self.hidden());
        for j in 0..h {
            for i in 0..n {
                self.iw[(j, i)] = p[j * (n + 1) + i];
            }
            self.b1[j] = p[j * (n + 1) + n];
        }
        let off = h * (n + 1);
        for k in 0..self.outputs() {
            for j in 0..h {
                self.lw[(k, j)] = p[off + k * (h + 1) + j];
            }
            self.b2[k] = p[off + k * (h + 1) + h];
        }
    }
}
