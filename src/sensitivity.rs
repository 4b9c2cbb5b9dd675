//! Forward sensitivities: the gradient of `V` by one linear solve per
//! parameter, kept as a reference and for comparison with the adjoint
//! method of [`crate::value`] (method.md section 2).
//!
//! Differentiating `(I - Q) x_T = b` with respect to one controller
//! probability `mu_k` gives, on the transient states `T`,
//!
//! ```text
//! (I - Q) dx_k = r_k,   r_k(m) = sum_m' dP(m' | m)/d mu_k x(m')   (m in T),
//! dV/d mu_k = sum_{m in T} p0(m) dx_k(m),
//! ```
//!
//! with `r_k` from the adjoint gradient pass of [`crate::value`] (`x` is 1 on
//! `B`, 0 on `Z`, and does not depend on `mu` there). This is the method
//! of gradient-based parameter synthesis in probabilistic model checkers
//! (one solve per parameter); the adjoint method computes the same numbers
//! with one transposed solve in total, `dV/d mu_k = sum_m y(m) r_k(m)`.
//! Both use the same matrix `I - Q`, so [`ForwardSensitivities`] factorises
//! it once (sparse LU) and then solves once per parameter.
//!
//! The derivatives with respect to the initial node distributions need no
//! solve in either method ([`crate::value::Evaluator::evaluate_with_gradient`]);
//! they are not repeated here.

use crate::controller::Probabilities;
use crate::solver::{LuSolver, SolveReport, SolverError};
use crate::value::{Evaluator, RowWorkspace, row_derivatives};

/// The right-hand sides `r_k` on `T` for every support entry of both
/// players, and the sparse LU of `I - Q`, ready for one solve per parameter.
pub struct ForwardSensitivities {
    solver: LuSolver,
    num_defender: usize,
    offsets: Vec<usize>,
    rhs: Vec<(u32, f64)>,
    p0: Vec<f64>,
    b: Vec<f64>,
    dx: Vec<f64>,
}

/// The gradient of `V` with respect to every support entry of both players
/// by forward sensitivities.
#[derive(Debug, Clone, PartialEq)]
pub struct ForwardGradient {
    /// `dV/d mu_def(g', u | g, o)` per defender support entry.
    pub defender: Vec<f64>,
    /// `dV/d mu_adv(h', v | h, o')` per adversary support entry.
    pub adversary: Vec<f64>,
    /// The largest residual `max_i |((I - Q) dx_k - r_k)_i|` over all solves.
    pub residual: f64,
}

impl ForwardSensitivities {
    /// Prepares the forward sensitivities at the evaluator's last evaluation,
    /// whose probabilities were `defender` and `adversary`: factorises
    /// `I - Q` (sparse LU, whatever solver the evaluator uses; solves are
    /// accepted up to the residual `tolerance`) and forms `r_k` on `T` for
    /// every parameter `k` in one pass over the transient rows.
    pub fn new(
        evaluator: &Evaluator,
        defender: &Probabilities,
        adversary: &Probabilities,
        tolerance: f64,
    ) -> Result<Self, SolverError> {
        let (pattern, values) = evaluator.system();
        let mut solver = LuSolver::new(pattern.clone(), tolerance)?;
        let n = pattern.n;
        if n > 0 {
            solver.factorize_with(|own, exits| {
                own.copy_from_slice(values);
                exits.copy_from_slice(evaluator.exits());
            })?;
        }
        let gmc = evaluator.gmc();
        let recurrence = evaluator.recurrence();
        let x = evaluator.state_values();
        let num_defender = defender.entries.len();
        let num_parameters = num_defender + adversary.entries.len();
        let (mut from_defender, mut from_adversary) = (Vec::new(), Vec::new());
        let mut work = RowWorkspace::for_chain(gmc);
        for (i, &m) in recurrence.transient.iter().enumerate() {
            let i = i as u32;
            row_derivatives(
                gmc,
                m,
                x,
                &mut work,
                |k, r| from_defender.push((k as u32, i, r)),
                |k, r| from_adversary.push(((num_defender + k) as u32, i, r)),
            );
        }
        let triples = from_defender.into_iter().chain(from_adversary);
        let mut offsets = vec![0; num_parameters + 1];
        let triples: Vec<(u32, u32, f64)> = triples.collect();
        for &(k, _, _) in &triples {
            offsets[k as usize + 1] += 1;
        }
        for k in 0..num_parameters {
            offsets[k + 1] += offsets[k];
        }
        let mut next = offsets.clone();
        let mut rhs = vec![(0, 0.0); triples.len()];
        for (k, i, r) in triples {
            rhs[next[k as usize]] = (i, r);
            next[k as usize] += 1;
        }
        let mut p0 = vec![0.0; n];
        for (m, p) in gmc.initial() {
            let i = recurrence.transient_index[m];
            if i != u32::MAX {
                p0[i as usize] += p;
            }
        }
        Ok(Self {
            solver,
            num_defender,
            offsets,
            rhs,
            p0,
            b: vec![0.0; n],
            dx: vec![0.0; n],
        })
    }

    /// The number of parameters: defender support entries, then adversary ones.
    pub fn num_parameters(&self) -> usize {
        self.offsets.len() - 1
    }

    /// `dV/d mu_k` for parameter `k` (defender entries `0..`, then adversary
    /// entries): one solve of `(I - Q) dx_k = r_k`, and its report.
    pub fn sensitivity(&mut self, k: usize) -> Result<(f64, SolveReport), SolverError> {
        let entries = &self.rhs[self.offsets[k]..self.offsets[k + 1]];
        if entries.is_empty() || self.b.is_empty() {
            let report = SolveReport {
                residual: 0.0,
                iterations: 0,
                error_bound: None,
            };
            return Ok((0.0, report));
        }
        self.b.fill(0.0);
        for &(i, r) in entries {
            self.b[i as usize] += r;
        }
        let report = self.solver.solve(&self.b, &mut self.dx)?;
        let derivative = self.p0.iter().zip(&self.dx).map(|(p, d)| p * d).sum();
        Ok((derivative, report))
    }

    /// The gradient with respect to every parameter of both players: one
    /// solve per parameter.
    pub fn gradient(&mut self) -> Result<ForwardGradient, SolverError> {
        let mut gradient = ForwardGradient {
            defender: Vec::with_capacity(self.num_defender),
            adversary: Vec::with_capacity(self.num_parameters() - self.num_defender),
            residual: 0.0,
        };
        for k in 0..self.num_parameters() {
            let (derivative, report) = self.sensitivity(k)?;
            gradient.residual = gradient.residual.max(report.residual);
            if k < self.num_defender {
                gradient.defender.push(derivative);
            } else {
                gradient.adversary.push(derivative);
            }
        }
        Ok(gradient)
    }
}
