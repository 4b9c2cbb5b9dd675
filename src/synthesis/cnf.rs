//! A formula in conjunctive normal form (CNF) and the incremental SAT solver
//! that decides it.
//!
//! [`Cnf`] numbers variables from 1 and stores clauses as DIMACS literals
//! (`v` or `-v`), so that an instance can be written as DIMACS for other
//! solvers ([`Cnf::write_dimacs`]). Literal 1 is the constant *true* (a unit
//! clause fixes it). A clause budget is checked while clauses are added, so
//! an instance too large for memory is an error before it is built.
//! [`Solver`] loads a `Cnf` into CaDiCaL (the `cadical` crate, which compiles
//! CaDiCaL 1.9 from source with the C++ compiler) and solves it under
//! assumptions, incrementally.

use std::io::Write;
use std::time::Instant;

use super::SynthesisError;

/// A literal in DIMACS form: `v` is variable `v`, `-v` its negation.
pub type Lit = i32;

/// The literal that is always true.
pub const TRUE: Lit = 1;

/// The literal that is always false.
pub const FALSE: Lit = -1;

/// A CNF formula under construction.
#[derive(Debug, Clone)]
pub struct Cnf {
    num_vars: i32,
    literals: Vec<Lit>,
    num_clauses: usize,
    clause_budget: usize,
}

impl Cnf {
    /// An empty formula (with the constant [`TRUE`]) that refuses to grow
    /// past `clause_budget` clauses.
    pub fn new(clause_budget: usize) -> Self {
        let mut cnf = Self {
            num_vars: 0,
            literals: Vec::new(),
            num_clauses: 0,
            clause_budget,
        };
        let truth = cnf.fresh();
        debug_assert_eq!(truth, TRUE);
        cnf.literals.extend([TRUE, 0]);
        cnf.num_clauses = 1;
        cnf
    }

    /// A new variable.
    pub fn fresh(&mut self) -> Lit {
        self.num_vars += 1;
        self.num_vars
    }

    /// `n` new variables.
    pub fn fresh_many(&mut self, n: usize) -> Vec<Lit> {
        (0..n).map(|_| self.fresh()).collect()
    }

    /// The number of variables.
    pub fn num_vars(&self) -> usize {
        self.num_vars as usize
    }

    /// The number of clauses.
    pub fn num_clauses(&self) -> usize {
        self.num_clauses
    }

    /// Adds the clause `l_1 | ... | l_k`, simplified by the constants: a
    /// clause with [`TRUE`] is dropped, [`FALSE`] literals are left out.
    pub fn clause(
        &mut self,
        literals: impl IntoIterator<Item = Lit>,
    ) -> Result<(), SynthesisError> {
        let start = self.literals.len();
        for lit in literals {
            if lit == TRUE {
                self.literals.truncate(start);
                return Ok(());
            }
            if lit != FALSE {
                self.literals.push(lit);
            }
        }
        self.literals.push(0);
        self.num_clauses += 1;
        if self.num_clauses > self.clause_budget {
            return Err(SynthesisError::TooLarge {
                what: "clauses".into(),
                budget: self.clause_budget,
            });
        }
        Ok(())
    }

    /// `a -> b`.
    pub fn implies(&mut self, a: Lit, b: Lit) -> Result<(), SynthesisError> {
        self.clause([-a, b])
    }

    /// A literal `d` with `d <-> (l_1 | ... | l_k)`, simplified by the
    /// constants: [`TRUE`] if some literal is, a single literal is its own
    /// disjunction, an empty one is [`FALSE`].
    pub fn or(&mut self, literals: &[Lit]) -> Result<Lit, SynthesisError> {
        if literals.contains(&TRUE) {
            return Ok(TRUE);
        }
        let literals: Vec<Lit> = literals.iter().copied().filter(|&l| l != FALSE).collect();
        match literals.as_slice() {
            [] => Ok(FALSE),
            [single] => Ok(*single),
            _ => {
                let d = self.fresh();
                self.clause(std::iter::once(-d).chain(literals.iter().copied()))?;
                for &l in &literals {
                    self.implies(l, d)?;
                }
                Ok(d)
            }
        }
    }

    /// A literal `c` with `c -> (l_1 & ... & l_k)` (one direction: `c` may
    /// be false when the conjunction holds; use it only where `c` is wanted
    /// true), simplified by the constants.
    pub fn and_implied(&mut self, literals: &[Lit]) -> Result<Lit, SynthesisError> {
        if literals.contains(&FALSE) {
            return Ok(FALSE);
        }
        let literals: Vec<Lit> = literals.iter().copied().filter(|&l| l != TRUE).collect();
        match literals.as_slice() {
            [] => return Ok(TRUE),
            [single] => return Ok(*single),
            _ => {}
        }
        let c = self.fresh();
        for &l in &literals {
            self.implies(c, l)?;
        }
        Ok(c)
    }

    /// The clauses from literal position `from` on (a clause start), each
    /// without its terminating 0 (an empty clause is an empty slice).
    fn clauses_from(&self, from: usize) -> impl Iterator<Item = &[Lit]> {
        self.literals[from..]
            .split_inclusive(|&l| l == 0)
            .map(|clause| &clause[..clause.len() - 1])
    }

    /// Writes the formula in DIMACS CNF, with `comments` as `c` lines.
    pub fn write_dimacs(&self, out: &mut impl Write, comments: &[String]) -> std::io::Result<()> {
        for comment in comments {
            writeln!(out, "c {comment}")?;
        }
        writeln!(out, "p cnf {} {}", self.num_vars, self.num_clauses)?;
        for clause in self.clauses_from(0) {
            for lit in clause {
                write!(out, "{lit} ")?;
            }
            writeln!(out, "0")?;
        }
        Ok(())
    }
}

/// The answer to one SAT call.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Answer {
    /// A model exists; read it with [`Solver::value`].
    Satisfiable,
    /// No model exists under the assumptions.
    Unsatisfiable,
}

/// CaDiCaL loaded with a [`Cnf`], solving incrementally under assumptions.
pub struct Solver {
    sat: cadical::Solver,
    loaded: usize,
    calls: usize,
    seconds: f64,
    deadline: Option<Instant>,
    created: Instant,
}

impl Solver {
    /// Loads `cnf`; every call gives up (an error) once `deadline` has passed.
    pub fn new(cnf: &Cnf, deadline: Option<Instant>) -> Self {
        let mut solver = Self {
            sat: cadical::Solver::new(),
            loaded: 0,
            calls: 0,
            seconds: 0.0,
            deadline,
            created: Instant::now(),
        };
        solver.load(cnf);
        solver
    }

    /// Adds the clauses `cnf` has gained since it was last loaded.
    pub fn load(&mut self, cnf: &Cnf) {
        self.sat.reserve(cnf.num_vars);
        for clause in cnf.clauses_from(self.loaded) {
            self.sat.add_clause(clause.iter().copied());
        }
        self.loaded = cnf.literals.len();
    }

    /// Solves under `assumptions` (literals taken as true for this call only).
    pub fn solve(&mut self, assumptions: &[Lit]) -> Result<Answer, SynthesisError> {
        let start = Instant::now();
        if let Some(deadline) = self.deadline {
            let left = deadline.saturating_duration_since(start).as_secs_f32();
            self.sat.set_callbacks(Some(cadical::Timeout::new(left)));
        }
        let answer = self.sat.solve_with(assumptions.iter().copied());
        self.calls += 1;
        self.seconds += start.elapsed().as_secs_f64();
        match answer {
            Some(true) => Ok(Answer::Satisfiable),
            Some(false) => Ok(Answer::Unsatisfiable),
            None => Err(SynthesisError::TimeBudget {
                calls: self.calls,
                seconds: self.created.elapsed().as_secs_f64(),
            }),
        }
    }

    /// The value of `lit` in the last model (after [`Answer::Satisfiable`]);
    /// a literal the model leaves open counts as false.
    pub fn value(&self, lit: Lit) -> bool {
        self.sat.value(lit) == Some(true)
    }

    /// The number of calls so far.
    pub fn calls(&self) -> usize {
        self.calls
    }

    /// Seconds spent inside the solver so far.
    pub fn seconds(&self) -> f64 {
        self.seconds
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn constants_simplify_clauses_and_or_is_an_equivalence() {
        let mut cnf = Cnf::new(100);
        let a = cnf.fresh();
        let b = cnf.fresh();
        cnf.clause([a, TRUE]).unwrap();
        assert_eq!(cnf.num_clauses(), 1, "a clause with TRUE is dropped");
        let d = cnf.or(&[a, b]).unwrap();
        let mut solver = Solver::new(&cnf, None);
        assert_eq!(solver.solve(&[d, -a]).unwrap(), Answer::Satisfiable);
        assert!(solver.value(b));
        assert_eq!(solver.solve(&[d, -a, -b]).unwrap(), Answer::Unsatisfiable);
        assert_eq!(solver.solve(&[-d, a]).unwrap(), Answer::Unsatisfiable);
        assert_eq!(cnf.or(&[]).unwrap(), FALSE);
    }

    #[test]
    fn the_clause_budget_is_an_error_not_an_abort() {
        let mut cnf = Cnf::new(2);
        let a = cnf.fresh();
        cnf.clause([a]).unwrap();
        assert!(matches!(
            cnf.clause([-a]),
            Err(SynthesisError::TooLarge { budget: 2, .. })
        ));
    }

    #[test]
    fn dimacs_lists_every_clause() {
        let mut cnf = Cnf::new(10);
        let a = cnf.fresh();
        cnf.clause([a, FALSE]).unwrap();
        let mut text = Vec::new();
        cnf.write_dimacs(&mut text, &["hello".into()]).unwrap();
        assert_eq!(
            String::from_utf8(text).unwrap(),
            "c hello\np cnf 2 2\n1 0\n2 0\n"
        );
    }
}
