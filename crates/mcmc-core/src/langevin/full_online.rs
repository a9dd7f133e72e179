//! Online MALA adaptation with a full preconditioner matrix (the paper's Fig. 2 "full"),
//! on nalgebra (feature `nalgebra`).

use nalgebra::DMatrix;

use super::adaptation::{diminishing_weights, Adaptation};
use super::gaussian::ProposalGaussian;
use super::params::LangevinParams;

/// Online adaptation with *full* preconditioning (section 5, eq. 13, the paper's Fig. 2
/// "full"): `G' = beta G + (1 - beta) g g^T`, `H = (1 - w1) I + w1 (delta I + G'^(1/2))`
/// (matrix square root by symmetric eigendecomposition), `M = H^-1`; momentum as
/// [`super::Online`]. Only on spaces that do not wrap (the images of a full Gaussian on the torus do
/// not factorise). Allocates per step: it exists for the 2-D comparison.
#[derive(Clone, Debug, PartialEq)]
pub struct FullOnline {
    g2: DMatrix<f64>,
    d: Vec<f64>,
    t: u64,
    diminishing: bool,
    frozen: bool,
}

impl FullOnline {
    /// Full online adaptation, with or without diminishing adaptation.
    #[must_use]
    pub fn new(diminishing: bool) -> Self {
        Self {
            g2: DMatrix::zeros(0, 0),
            d: Vec::new(),
            t: 0,
            diminishing,
            frozen: false,
        }
    }

    fn ensure_dim(&mut self, n: usize) {
        if self.d.len() != n {
            self.g2 = DMatrix::zeros(n, n);
            self.d = vec![0.0; n];
        }
    }
}

impl Adaptation for FullOnline {
    fn name(&self) -> &'static str {
        "full-online"
    }
    fn needs_gradient(&self, _dim: usize) -> bool {
        true
    }
    fn gaussian(
        &mut self,
        params: &LangevinParams,
        _u: &[f64],
        g: &[f64],
        out: &mut ProposalGaussian,
    ) -> bool {
        let n = g.len();
        self.ensure_dim(n);
        let (w1, w2) = diminishing_weights(params, self.t, self.diminishing);
        let gv = nalgebra::DVector::from_column_slice(g);
        let g2 = &self.g2 * params.beta + (&gv * gv.transpose()) * (1.0 - params.beta);
        let eig = nalgebra::SymmetricEigen::new(g2);
        let sqrt_vals = eig.eigenvalues.map(|v| v.max(0.0).sqrt());
        let sqrt_g =
            &eig.eigenvectors * DMatrix::from_diagonal(&sqrt_vals) * eig.eigenvectors.transpose();
        let identity = DMatrix::<f64>::identity(n, n);
        let h = &identity * (1.0 - w1) + (&identity * params.delta + sqrt_g) * w1;
        let Some(m) = h.try_inverse() else {
            return out.set_full(params, &identity, g);
        };
        let m = (&m + m.transpose()) * 0.5;
        let drift: Vec<f64> = (0..n)
            .map(|i| g[i] + w2 * (params.alpha * self.d[i] + (1.0 - params.alpha) * g[i]))
            .collect();
        out.set_full(params, &m, &drift)
    }
    fn adapt(&mut self, params: &LangevinParams, _u: &[f64], g: &[f64], _first_visit: bool) {
        if self.frozen {
            return;
        }
        self.ensure_dim(g.len());
        let gv = nalgebra::DVector::from_column_slice(g);
        self.g2 = &self.g2 * params.beta + (&gv * gv.transpose()) * (1.0 - params.beta);
        for (d, &gi) in self.d.iter_mut().zip(g) {
            *d = params.alpha * *d + (1.0 - params.alpha) * gi;
        }
        self.t += 1;
    }
    fn freeze(&mut self) {
        self.frozen = true;
    }
    fn is_frozen(&self) -> bool {
        self.frozen
    }
}
