//! The multiple-importance-sampling heuristics (Veach 1997): the per-technique weight shared
//! by the one-query drivers (`mis.rs`) and the batch path (`batch.rs`).

/// The multiple-importance-sampling weight of a technique.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum MisHeuristic {
    /// `w_a = n_a p_a / Σ_k n_k p_k`.
    Balance,
    /// `w_a = (n_a p_a)² / Σ_k (n_k p_k)²`.
    Power,
}

impl MisHeuristic {
    /// Both heuristics, in report order.
    pub const ALL: [MisHeuristic; 2] = [MisHeuristic::Balance, MisHeuristic::Power];

    /// The weight of a technique of two: `own = n_a p_a`, `other = n_b p_b` at the same
    /// direction. `weight(a, b) + weight(b, a) = 1` whenever `a + b > 0` (the condition that
    /// makes MIS unbiased).
    pub fn weight(self, own: f64, other: f64) -> f64 {
        match self {
            MisHeuristic::Balance => own / (own + other),
            MisHeuristic::Power => own * own / (own * own + other * other),
        }
    }

    /// `balance` or `power`.
    pub fn as_str(self) -> &'static str {
        match self {
            MisHeuristic::Balance => "balance",
            MisHeuristic::Power => "power",
        }
    }

    /// The estimator's name: `mis-balance` or `mis-power`.
    pub fn estimator_name(self) -> &'static str {
        match self {
            MisHeuristic::Balance => "mis-balance",
            MisHeuristic::Power => "mis-power",
        }
    }

    /// The heuristic of `balance` / `power` (or `mis-balance` / `mis-power`).
    pub fn parse(s: &str) -> Option<Self> {
        match s.strip_prefix("mis-").unwrap_or(s) {
            "balance" => Some(MisHeuristic::Balance),
            "power" => Some(MisHeuristic::Power),
            _ => None,
        }
    }
}
