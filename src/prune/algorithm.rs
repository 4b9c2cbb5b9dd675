//! Algorithm 1, line by line.
//!
//! Cost: the initial GMC, its SCCs and its reverse graph are built once
//! (`O(|GMC states| + |GMC edges|)`). For one `(C, i)` the loop visits, for
//! each bad state `m'`, only the predecessors of `m'` (and, with adversary
//! pruning, of the chosen good state `m''`): a source without an edge into
//! `m'` under the initial structures makes no term of Equation (BigEqn1)
//! positive. Each visited source costs one pass over its terms. The check of
//! lines 27-30 builds one GMC per distinct structure (cached).

use rustc_hash::FxHashMap;

use crate::automaton::Dra;
use crate::controller::{Fsc, Role, Support};
use crate::game::Posg;
use crate::graph::{Components, bottom_components, reverse_csr, strongly_connected_components};
use crate::product::{Gmc, GmcState};

use super::equations::Terms;
use super::indicator::{Indicator, LastOption};
use super::{Attempt, LastOptionStop, PruneError, PruneReport, PruneSettings, Structure};

/// Runs Algorithm 1 from the initial structures `I^o_def = supp(defender)`
/// and `I^o_adv = supp(adversary)` (the initial node distributions are kept).
///
/// * Line 1: the GMC reachable under the initial structures ([`Gmc::build`]).
/// * Line 3: its SCCs.
/// * Lines 4-7, per SCC `C` and pair `(L_i, K_i)`:
///   `Bad_i = {m' not in C : m -> m' for some m in C} U (C n L_i x G_def x G_adv)`,
///   `Good_i = C n (K_i x G_def x G_adv)`; pairs with an empty `Good_i` are
///   skipped (line 29 could not hold).
/// * Line 8: the indicators restart from the initial structures.
/// * Lines 9-26: the bad states are taken in increasing GMC order; the `n`-th
///   chooses the good state `Good_i[n mod |Good_i|]`. The sources `m` range
///   over `C` minus the `Bad_i` of lines 5-6, so that the removals do not
///   depend on the order in which bad states are chosen.
/// * Lines 27-30: the structure is kept iff some `Good_i` state, identified
///   by its `(s, q, g, h)`, lies in a BSCC of the new GMC that misses `L_i`
///   (so that BSCC is phi-feasible through pair `i`: the paper's Proposition).
///   After a completed loop no edge leads from `C \ Bad_i` into `Bad_i`, so
///   a recurrent good state outside `L_i` always satisfies this; the extra
///   condition matters for good states inside `L_i` (when `K_i` meets `L_i`)
///   and after a [`LastOptionStop`].
pub fn prune(
    game: &Posg,
    dra: &Dra,
    defender: &Fsc,
    adversary: &Fsc,
    settings: &PruneSettings,
) -> Result<PruneReport, PruneError> {
    check_role(Role::Defender, defender)?;
    check_role(Role::Adversary, adversary)?;
    let supports = (Support::of(defender), Support::of(adversary));
    let gmc = Gmc::build(game, dra, &supports.0, &supports.1)?;
    let components = strongly_connected_components(&gmc.graph());
    let predecessors = reverse_csr(&gmc.graph());
    let mut run = Run {
        game,
        dra,
        settings: *settings,
        initial: (defender, adversary),
        supports: &supports,
        terms: Terms::new(game, dra),
        gmc: &gmc,
        components: &components,
        predecessors: &predecessors,
        bad_mark: vec![0; gmc.num_states()],
        stamp: 0,
        checked: FxHashMap::default(),
        report: PruneReport {
            settings: *settings,
            gmc_states: gmc.num_states(),
            sccs: components.count,
            skipped: 0,
            attempts: Vec::new(),
            structures: Vec::new(),
        },
    };
    for (c, members) in components.members().iter().enumerate() {
        let exits = run.exits(c, members);
        for i in 0..dra.pairs().len() {
            run.attempt(c, members, &exits, i)?;
        }
    }
    Ok(run.report)
}

fn check_role(expected: Role, fsc: &Fsc) -> Result<(), PruneError> {
    if fsc.role() == expected {
        Ok(())
    } else {
        Err(PruneError::Role {
            expected,
            found: fsc.role(),
        })
    }
}

/// The new GMC of a structure (lines 27-28), reduced to what line 29 asks:
/// which BSCC each recurrent state is in, and which pairs each BSCC avoids.
struct Checked {
    controllers: (Fsc, Fsc),
    bscc_of: FxHashMap<GmcState, usize>,
    misses_fin: Vec<Vec<bool>>,
    structure: Option<usize>,
}

type Key = (Vec<bool>, Vec<bool>);

struct Run<'a> {
    game: &'a Posg,
    dra: &'a Dra,
    settings: PruneSettings,
    initial: (&'a Fsc, &'a Fsc),
    supports: &'a (Support, Support),
    terms: Terms<'a>,
    gmc: &'a Gmc,
    components: &'a Components,
    predecessors: &'a (Vec<usize>, Vec<u32>),
    bad_mark: Vec<u32>,
    stamp: u32,
    checked: FxHashMap<Key, Checked>,
    report: PruneReport,
}

impl Run<'_> {
    /// Line 5: the states outside SCC `c` with an edge from inside, increasing.
    fn exits(&self, c: usize, members: &[usize]) -> Vec<usize> {
        let graph = self.gmc.graph();
        let mut exits: Vec<usize> = members
            .iter()
            .flat_map(|&m| graph.targets[graph.offsets[m]..graph.offsets[m + 1]].iter())
            .map(|&t| t as usize)
            .filter(|&t| self.components.component[t] as usize != c)
            .collect();
        exits.sort_unstable();
        exits.dedup();
        exits
    }

    fn predecessors(&self, m: usize) -> &[u32] {
        let (offsets, targets) = self.predecessors;
        &targets[offsets[m]..offsets[m + 1]]
    }

    fn automaton_state(&self, m: usize) -> usize {
        self.gmc.state(m).q as usize
    }

    /// Lines 5-30 for SCC `c` and pair `i`.
    fn attempt(
        &mut self,
        c: usize,
        members: &[usize],
        exits: &[usize],
        i: usize,
    ) -> Result<(), PruneError> {
        let pair = &self.dra.pairs()[i];
        let good: Vec<usize> = members
            .iter()
            .copied()
            .filter(|&m| pair.inf[self.automaton_state(m)])
            .collect();
        if good.is_empty() {
            self.report.skipped += 1;
            return Ok(());
        }
        let mut bad: Vec<usize> = members
            .iter()
            .copied()
            .filter(|&m| pair.fin[self.automaton_state(m)])
            .chain(exits.iter().copied())
            .collect();
        bad.sort_unstable();
        self.stamp += 1;
        for &m in &bad {
            self.bad_mark[m] = self.stamp;
        }
        let mut defender = Indicator::full(&self.supports.0);
        let mut adversary = Indicator::full(&self.supports.1);
        let stop = self.remove_toward_bad(c, &bad, &good, &mut defender, &mut adversary);
        let structure = self.keep_if_recurrent(i, &good, &defender, &adversary)?;
        let index = self.report.attempts.len();
        if let Some(s) = structure {
            self.report.structures[s].attempts.push(index);
        }
        self.report.attempts.push(Attempt {
            scc: c,
            scc_size: members.len(),
            pair: i,
            bad: bad.len(),
            good: good.len(),
            removed_defender: defender.removed(),
            removed_adversary: adversary.removed(),
            stop,
            structure,
        });
        Ok(())
    }

    /// Whether `m` is in `C \ Bad_i` (the sources of line 11).
    fn is_source(&self, c: usize, m: usize) -> bool {
        self.components.component[m] as usize == c && self.bad_mark[m] != self.stamp
    }

    /// Lines 9-26. Returns the stop at line 9's guard, if any.
    fn remove_toward_bad(
        &self,
        c: usize,
        bad: &[usize],
        good: &[usize],
        defender: &mut Indicator<'_>,
        adversary: &mut Indicator<'_>,
    ) -> Option<LastOptionStop> {
        let mut entries = Vec::new();
        let mut widened = Vec::new();
        for (n, &target) in bad.iter().enumerate() {
            let chosen_good = good[n % good.len()];
            let into_bad = self.predecessors(target);
            let into_good: &[u32] = if self.settings.prune_adversary {
                self.predecessors(chosen_good)
            } else {
                &[]
            };
            let (to, toward) = (self.gmc.state(target), self.gmc.state(chosen_good));
            for m in merged(into_bad, into_good) {
                if !self.is_source(c, m) {
                    continue;
                }
                let from = self.gmc.state(m);
                if into_bad.binary_search(&(m as u32)).is_ok() {
                    entries.clear();
                    self.terms
                        .defender_entries_into(from, to, defender, adversary, &mut entries);
                    let removal = if self.settings.paper_literal {
                        widened.clear();
                        self.terms
                            .same_action_and_observation(&entries, defender, &mut widened);
                        &widened
                    } else {
                        &entries
                    };
                    if let Err(last) = remove_all(defender, removal) {
                        return Some(stop(to, Role::Defender, defender, last));
                    }
                }
                if into_good.binary_search(&(m as u32)).is_ok() {
                    entries.clear();
                    self.terms.adversary_entries_toward_good(
                        from,
                        toward,
                        defender,
                        adversary,
                        &mut entries,
                    );
                    if let Err(last) = remove_all(adversary, &entries) {
                        return Some(stop(to, Role::Adversary, adversary, last));
                    }
                }
            }
        }
        None
    }

    /// Lines 27-30: builds (or recalls) the GMC under the new structure and
    /// returns the index of the kept structure, if a `Good_i` state lies in a
    /// BSCC that misses `L_i`.
    fn keep_if_recurrent(
        &mut self,
        i: usize,
        good: &[usize],
        defender: &Indicator<'_>,
        adversary: &Indicator<'_>,
    ) -> Result<Option<usize>, PruneError> {
        let key = (defender.key().to_vec(), adversary.key().to_vec());
        let mut checked = match self.checked.remove(&key) {
            Some(checked) => checked,
            None => self.check(defender, adversary)?,
        };
        let witness = good.iter().map(|&m| self.gmc.state(m)).find(|state| {
            checked
                .bscc_of
                .get(state)
                .is_some_and(|&b| checked.misses_fin[b][i])
        });
        if let (Some(witness), None) = (witness, checked.structure) {
            checked.structure = Some(self.report.structures.len());
            self.report.structures.push(Structure {
                defender: checked.controllers.0.clone(),
                adversary: checked.controllers.1.clone(),
                witness,
                attempts: Vec::new(),
            });
        }
        let kept = witness.and(checked.structure);
        self.checked.insert(key, checked);
        Ok(kept)
    }

    /// Lines 27-28: the GMC under uniform controllers on the structure, its
    /// SCCs and bottom SCCs (the recurrence classes).
    fn check(
        &self,
        defender: &Indicator<'_>,
        adversary: &Indicator<'_>,
    ) -> Result<Checked, PruneError> {
        let controllers = (
            defender.uniform_fsc(self.initial.0)?,
            adversary.uniform_fsc(self.initial.1)?,
        );
        let gmc = Gmc::build(
            self.game,
            self.dra,
            &Support::of(&controllers.0),
            &Support::of(&controllers.1),
        )?;
        let graph = gmc.graph();
        let components = strongly_connected_components(&graph);
        let bottom = bottom_components(&graph, &components);
        let mut bscc_of = FxHashMap::default();
        let mut misses_fin = Vec::new();
        for (c, members) in components.members().iter().enumerate() {
            if !bottom[c] {
                continue;
            }
            let b = misses_fin.len();
            misses_fin.push(
                self.dra
                    .pairs()
                    .iter()
                    .map(|pair| members.iter().all(|&m| !pair.fin[gmc.state(m).q as usize]))
                    .collect(),
            );
            bscc_of.extend(members.iter().map(|&m| (gmc.state(m), b)));
        }
        Ok(Checked {
            controllers,
            bscc_of,
            misses_fin,
            structure: None,
        })
    }
}

/// The union of two increasing index lists, increasing, without repeats.
fn merged(a: &[u32], b: &[u32]) -> Vec<usize> {
    let mut all: Vec<usize> = a.iter().chain(b).map(|&m| m as usize).collect();
    all.sort_unstable();
    all.dedup();
    all
}

/// Removes every listed entry, stopping at the first that is a block's last option.
fn remove_all(indicator: &mut Indicator<'_>, entries: &[usize]) -> Result<(), LastOption> {
    entries.iter().try_for_each(|&k| indicator.remove(k))
}

fn stop(
    bad_state: GmcState,
    player: Role,
    indicator: &Indicator<'_>,
    last: LastOption,
) -> LastOptionStop {
    let observations = indicator.support().num_observations();
    LastOptionStop {
        bad_state,
        player,
        node: last.block / observations,
        observation: last.block % observations,
        entry: indicator.support().entry(last.entry),
    }
}
