//! A small unconstrained L-BFGS minimiser (Nocedal & Wright 2006, Alg. 7.4/7.5) with a
//! backtracking Armijo line search.
//!
//! The SRBF fit is made bound-free by reparametrisation (see [`super::fit`]), so plain L-BFGS
//! suffices; a self-contained one avoids a dependency for ~100 lines and keeps f64 throughout.

/// Outcome of a minimisation.
#[derive(Debug, Clone)]
pub(crate) struct Minimum {
    /// The best point found.
    pub(crate) x: Vec<f64>,
    /// Iterations run.
    pub(crate) iterations: usize,
    /// Whether a stopping test (gradient or relative decrease) was met before `max_iter`.
    pub(crate) converged: bool,
}

/// Stopping rules.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Stop {
    /// Iteration cap.
    pub(crate) max_iter: usize,
    /// Stop when `max |∇f| < grad_tol`.
    pub(crate) grad_tol: f64,
    /// Stop when the objective decreases by less than `rel_tol · |f|` in each of
    /// [`STALL_ITERATIONS`] consecutive iterations.
    pub(crate) rel_tol: f64,
}

const MEMORY: usize = 8;

/// Consecutive iterations of negligible decrease that count as convergence.
const STALL_ITERATIONS: usize = 5;

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Minimises `f` from `x0`; `f(x, grad)` returns the value and writes the gradient.
/// A non-finite value counts as +∞ for the line search.
pub(crate) fn minimise(
    mut f: impl FnMut(&[f64], &mut [f64]) -> f64,
    x0: Vec<f64>,
    stop: Stop,
) -> Minimum {
    let n = x0.len();
    let mut x = x0;
    let mut g = vec![0.0; n];
    let mut fx = f(&x, &mut g);
    let mut s_hist: Vec<Vec<f64>> = Vec::new();
    let mut y_hist: Vec<Vec<f64>> = Vec::new();
    let mut rho: Vec<f64> = Vec::new();
    let mut x_new = vec![0.0; n];
    let mut g_new = vec![0.0; n];
    let mut converged = false;
    let mut iterations = 0;
    let mut small_steps = 0;
    if !fx.is_finite() {
        return Minimum {
            x,
            iterations,
            converged,
        };
    }
    while iterations < stop.max_iter {
        if g.iter().fold(0.0f64, |m, v| m.max(v.abs())) < stop.grad_tol {
            converged = true;
            break;
        }
        iterations += 1;
        // Two-loop recursion: d = −H g.
        let mut q = g.clone();
        let k = s_hist.len();
        let mut alpha = vec![0.0; k];
        for i in (0..k).rev() {
            alpha[i] = rho[i] * dot(&s_hist[i], &q);
            for (qj, yj) in q.iter_mut().zip(&y_hist[i]) {
                *qj -= alpha[i] * yj;
            }
        }
        let gamma = if k > 0 {
            dot(&s_hist[k - 1], &y_hist[k - 1]) / dot(&y_hist[k - 1], &y_hist[k - 1])
        } else {
            1.0 / g.iter().map(|v| v * v).sum::<f64>().sqrt().max(1.0)
        };
        for v in q.iter_mut() {
            *v *= gamma;
        }
        for i in 0..k {
            let beta = rho[i] * dot(&y_hist[i], &q);
            for (qj, sj) in q.iter_mut().zip(&s_hist[i]) {
                *qj += (alpha[i] - beta) * sj;
            }
        }
        let mut d: Vec<f64> = q.iter().map(|v| -v).collect();
        let mut slope = dot(&g, &d);
        if !(slope < 0.0) {
            // Not a descent direction: restart from steepest descent.
            s_hist.clear();
            y_hist.clear();
            rho.clear();
            d = g.iter().map(|v| -v).collect();
            slope = dot(&g, &d);
        }
        // Backtracking Armijo line search.
        let mut step = 1.0;
        let mut accepted = false;
        let mut f_new = f64::INFINITY;
        for _ in 0..40 {
            for ((xn, xi), di) in x_new.iter_mut().zip(&x).zip(&d) {
                *xn = xi + step * di;
            }
            f_new = f(&x_new, &mut g_new);
            if f_new.is_finite() && f_new <= fx + 1e-4 * step * slope {
                accepted = true;
                break;
            }
            step *= 0.5;
        }
        if !accepted {
            converged = s_hist.is_empty();
            if s_hist.is_empty() {
                break;
            }
            s_hist.clear();
            y_hist.clear();
            rho.clear();
            continue;
        }
        let s: Vec<f64> = x_new.iter().zip(&x).map(|(a, b)| a - b).collect();
        let y: Vec<f64> = g_new.iter().zip(&g).map(|(a, b)| a - b).collect();
        let sy = dot(&s, &y);
        if sy > 1e-300 {
            if s_hist.len() == MEMORY {
                s_hist.remove(0);
                y_hist.remove(0);
                rho.remove(0);
            }
            rho.push(1.0 / sy);
            s_hist.push(s);
            y_hist.push(y);
        }
        let decrease = fx - f_new;
        std::mem::swap(&mut x, &mut x_new);
        std::mem::swap(&mut g, &mut g_new);
        fx = f_new;
        if decrease <= stop.rel_tol * fx.abs().max(1e-300) {
            small_steps += 1;
            if small_steps >= STALL_ITERATIONS {
                converged = true;
                break;
            }
        } else {
            small_steps = 0;
        }
    }
    Minimum {
        x,
        iterations,
        converged,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn minimises_rosenbrock() {
        let m = minimise(
            |x, g| {
                let (a, b) = (x[0], x[1]);
                g[0] = -2.0 * (1.0 - a) - 400.0 * a * (b - a * a);
                g[1] = 200.0 * (b - a * a);
                (1.0 - a).powi(2) + 100.0 * (b - a * a).powi(2)
            },
            vec![-1.2, 1.0],
            Stop {
                max_iter: 500,
                grad_tol: 1e-10,
                rel_tol: 0.0,
            },
        );
        assert!(m.converged);
        assert!(
            (m.x[0] - 1.0).abs() < 1e-6 && (m.x[1] - 1.0).abs() < 1e-6,
            "{:?}",
            m.x
        );
    }
}
