//! Tests of the query rule (`query_rule.rs`): the authors' ranking, the product's window and
//! ceiling, the silence wake, and their checkpoints.

use super::super::ask_pacing::AskPacing;
use super::*;

const A: AbstractState = AbstractState(0b01);
const B: AbstractState = AbstractState(0b10);
const C: AbstractState = AbstractState(0b11);

#[test]
fn the_first_step_always_asks() {
    for form in [UcbForm::Authors, UcbForm::Paper] {
        assert!(QueryRule::new(0.1, 0, form).should_query(A));
    }
}

#[test]
fn running_mean_of_absolute_error_per_state() {
    let mut rule = QueryRule::new(0.1, 2, UcbForm::Authors);
    rule.record(A, 1.0, 0.5);
    rule.record(A, -1.0, 0.0);
    rule.record(B, 0.0, 0.25);
    assert_eq!(rule.total_feedback(), 3);
    assert_eq!(
        rule.stats(A),
        StateStats {
            count: 2,
            mean_error: 0.75
        }
    );
    assert_eq!(
        rule.stats(B),
        StateStats {
            count: 1,
            mean_error: 0.25
        }
    );
}

#[test]
fn authors_score_matches_the_formula() {
    let mut rule = QueryRule::new(0.2, 4, UcbForm::Authors);
    rule.record(A, 1.0, 0.5);
    rule.record(A, 1.0, 0.7);
    rule.record(B, -1.0, 0.0);
    // N = 3; A: N(g) = 2, mean 0.4; B: N(g) = 1, mean 1.0; C unseen.
    let close = |x: f64, y: f64| (x - y).abs() < 1e-6;
    assert!(close(rule.score(A), 0.4 + 0.2 * (6.0f64 / 3.0).sqrt()));
    assert!(close(rule.score(B), 1.0 + 0.2 * (6.0f64 / 2.0).sqrt()));
    assert!(close(rule.score(C), 0.2 * 6.0f64.sqrt()));
}

#[test]
fn paper_score_uses_squared_error_and_log_count() {
    let mut rule = QueryRule::new(0.2, 4, UcbForm::Paper);
    rule.record(A, 1.0, 0.5);
    rule.record(B, -1.0, 0.0);
    rule.record(B, 1.0, 0.0);
    let close = |x: f64, y: f64| (x - y).abs() < 1e-6;
    assert!(close(
        rule.score(A),
        0.25 + 0.2 * (2.0 * 3.0f64.ln() / 1.0).sqrt()
    ));
    assert!(close(
        rule.score(B),
        1.0 + 0.2 * (2.0 * 3.0f64.ln() / 2.0).sqrt()
    ));
    assert_eq!(rule.score(C), f64::INFINITY);
    assert!(rule.should_query(C));
}

#[test]
fn asks_only_when_at_most_k_seen_states_score_higher() {
    // Three seen states with clearly ordered errors, tiny exploration bonus.
    let mut rule = QueryRule::new(1e-6, 0, UcbForm::Authors);
    let low = AbstractState(4);
    rule.record(A, 1.0, 0.0); // error 1.0
    rule.record(B, 1.0, 0.5); // error 0.5
    rule.record(low, 1.0, 0.9); // error 0.1
    assert!(rule.should_query(A), "top state is asked with k = 0");
    assert!(!rule.should_query(B), "one state scores higher, k = 0");
    rule.k = 1;
    assert!(rule.should_query(B));
    assert!(!rule.should_query(low), "two states score higher, k = 1");
    rule.k = 2;
    assert!(rule.should_query(low));
}

#[test]
fn an_unseen_state_gets_the_largest_bonus() {
    let mut rule = QueryRule::new(0.1, 0, UcbForm::Authors);
    for _ in 0..50 {
        rule.record(A, 1.0, 1.0); // perfectly predicted: error 0
    }
    assert!(rule.score(C) > rule.score(A));
    assert!(rule.should_query(C));
}

#[test]
fn a_well_predicted_state_stops_being_asked() {
    let mut rule = QueryRule::new(0.1, 0, UcbForm::Authors);
    rule.record(B, 1.0, -1.0); // B is badly predicted: error 2
    for _ in 0..20 {
        rule.record(A, 1.0, 0.95);
    }
    assert!(!rule.should_query(A));
    assert!(rule.should_query(B));
}

#[test]
fn survives_a_serde_round_trip() {
    let mut rule = QueryRule::new(0.2, 60, UcbForm::Paper);
    rule.record(A, 1.0, 0.0);
    let back: QueryRule = serde_json::from_str(&serde_json::to_string(&rule).unwrap()).unwrap();
    assert_eq!(back, rule);
}

#[test]
fn with_at_most_k_plus_one_states_seen_every_state_is_asked() {
    // Only other seen states can outrank g, so with k + 1 of them or fewer seen the rank
    // test always passes: DREF asks at every step until a (k + 2)-th state has feedback.
    let (a, b, c, d) = (
        AbstractState(1),
        AbstractState(2),
        AbstractState(3),
        AbstractState(4),
    );
    let mut rule = QueryRule::new(0.1, 2, UcbForm::Authors);
    for _ in 0..500 {
        rule.record(a, 1.0, 1.0);
    }
    rule.record(b, 1.0, -1.0);
    rule.record(c, 1.0, -1.0);
    // `a` has by far the lowest score of the three, and is still asked.
    assert!(rule.score(a) < rule.score(b) && rule.score(a) < rule.score(c));
    assert!(rule.should_query(a));
    // A fourth state with feedback puts three above `a`: it is no longer asked.
    rule.record(d, 1.0, -1.0);
    assert!(!rule.should_query(a));
    assert!(rule.should_query(d));
}

/// The freeze of the authors' rule: states ranked high by early answers are never visited
/// again, and the one the learner now visits ranks below k of them for good.
fn frozen_history(rule: &mut QueryRule) -> AbstractState {
    for g in 1..=5 {
        rule.record(AbstractState(g), 1.0, -1.0); // badly predicted: error 2
    }
    let now = AbstractState(9);
    for _ in 0..50 {
        rule.record(now, 1.0, 1.0); // well predicted: error 0, and many answers
    }
    now
}

#[test]
fn the_authors_rule_freezes_and_the_recent_rank_does_not() {
    let mut authors = QueryRule::new(0.1, 2, UcbForm::Authors);
    let now = frozen_history(&mut authors);
    assert!(
        (0..5_000).all(|_| !authors.visit(now)),
        "the authors' rule asks again"
    );

    let mut recent = QueryRule::new(0.1, 2, UcbForm::Authors).ranked_among_recent(100);
    let now = frozen_history(&mut recent);
    // Only the states visited in the window compete: the learner's own state is the best.
    assert!(recent.visit(now));
    let asked = (0..5_000).filter(|_| recent.visit(now)).count();
    assert_eq!(
        asked, 5_000,
        "nothing else is recent, so every visit may ask"
    );
}

#[test]
fn a_waking_rule_keeps_the_authors_ranking_until_a_silence_and_then_asks_once() {
    let mut rule = QueryRule::new(0.1, 2, UcbForm::Authors).waking_after(1_000);
    let now = frozen_history(&mut rule);
    let mut asked_at = Vec::new();
    for step in 1..=3_500u64 {
        if rule.visit(now) {
            rule.record(now, 1.0, 1.0);
            asked_at.push(step);
        }
    }
    // Silent as the authors' rule for 999 steps, then one query per 1,000 steps: the
    // silence's only state is its best, and the answer ends the silence.
    assert_eq!(asked_at, [1_000, 2_000, 3_000]);
    assert_eq!(rule.silent_steps(), Some(500));
}

#[test]
fn a_paced_opening_ranks_as_if_woken_and_asks_its_share_of_a_frozen_history() {
    // The frozen history silences the authors' ranking; with a paced opening of 3,000 steps at
    // a quarter of them the rule asks from the first steps, every fourth step at most.
    let budget = AskBudget::new(0.1, 20)
        .opening_for(3_000)
        .starting_empty()
        .opening_at(0.25);
    let mut rule = QueryRule::new(0.1, 2, UcbForm::Authors)
        .waking_after(1_000)
        .with_ceiling(budget);
    let now = frozen_history(&mut rule);
    let mut asked_at = Vec::new();
    for step in 1..=3_000u64 {
        if rule.visit(now) {
            rule.record(now, 1.0, 1.0);
            asked_at.push(step);
        }
    }
    assert_eq!(asked_at.len(), 750);
    assert_eq!(asked_at[..3], [4, 8, 12]);
    // After the opening, the debt (750 asked, 300 earned) silences it as any opening's: the
    // authors' ranking again, and no token for the wake to spend.
    assert!((3_001..=5_000u64).all(|_| !rule.visit(now)));
    // Without the pacing the same opening asks nothing: the authors' ranking is frozen.
    let open = AskBudget::new(0.1, 20).opening_for(3_000).starting_empty();
    let mut authors = QueryRule::new(0.1, 2, UcbForm::Authors)
        .waking_after(1_000)
        .with_ceiling(open);
    let now = frozen_history(&mut authors);
    let asked = (1..=999).filter(|_| authors.visit(now)).count();
    assert_eq!(asked, 0);
}

/// A paced opening of 4,000 steps at a quarter of them on a learner that is in A three steps
/// of four and in B the fourth, every answer as badly predicted: `(asked in A, asked in B)`.
fn opening_split(by_visits: bool) -> (u64, u64) {
    let budget = AskBudget::new(0.1, 20)
        .opening_for(4_000)
        .starting_empty()
        .opening_at(0.25);
    let mut rule = QueryRule::new(0.2, 4, UcbForm::Authors)
        .waking_after(1_000)
        .with_ceiling(budget);
    if by_visits {
        rule = rule.opening_by_visits();
    }
    let mut asked = (0, 0);
    for step in 0..4_000u64 {
        let g = if step % 4 == 3 { B } else { A };
        if rule.visit(g) {
            rule.record(g, 1.0, 0.0);
            if g == A {
                asked.0 += 1;
            } else {
                asked.1 += 1;
            }
        }
    }
    asked
}

#[test]
fn a_paced_opening_by_visits_asks_each_state_its_share_of_its_visits() {
    // By visits: a quarter of A's 3,000 visits and of B's 1,000, as a draw at random steps
    // would place them (the bucket, empty at the start, costs the first query or so).
    let (a, b) = opening_split(true);
    assert!(
        (748..=750).contains(&a) && (249..=250).contains(&b),
        "{a}, {b}"
    );
    // Ranked, the score's count term lifts the state with fewer answers: the opening's answers
    // are evened out over the states, as many in B as in A (half of B's visits, a sixth of A's).
    let (a, b) = opening_split(false);
    assert!(
        a + b >= 990,
        "the ranked opening spends its share too: {a} + {b}"
    );
    assert!(a.abs_diff(b) <= 2, "{a}, {b}");
}

#[test]
fn a_tapered_opening_by_visits_asks_each_state_the_rate_of_its_own_visits() {
    // 4,000 steps tapered from a half to nothing: about 1,000 asked, 750 of them in the first
    // 2,000 steps. The learner is in A for those, then in A and B by turns.
    let budget = AskBudget::new(0.1, 20)
        .opening_for(4_000)
        .starting_empty()
        .opening_at(0.5)
        .tapering();
    let mut rule = QueryRule::new(0.2, 4, UcbForm::Authors)
        .waking_after(1_000)
        .with_ceiling(budget)
        .opening_by_visits();
    let (mut first, mut later) = (0, (0, 0));
    for step in 0..4_000u64 {
        let g = if step >= 2_000 && step % 2 == 1 { B } else { A };
        if rule.visit(g) {
            rule.record(g, 1.0, 0.0);
            match (step < 2_000, g == A) {
                (true, _) => first += 1,
                (false, true) => later.0 += 1,
                (false, false) => later.1 += 1,
            }
        }
    }
    assert!((748..=751).contains(&first), "{first}");
    // Each is owed about 125 of the last 250: A, with 750 answers for its first 2,000 visits,
    // is still asked the later rate of its later visits (owed at today's rate times all its
    // visits, about 0.1 * 3,000 by then, it would not be asked again).
    assert!(
        (118..=127).contains(&later.0) && (118..=127).contains(&later.1),
        "{later:?}"
    );
}

/// After a paced opening of 1,000 steps at half of them (500 asked, 100 earned: a debt of 400)
/// on the same 3:1 learner, the ceiling's 10 % repaid half from its earnings: the debt is paid
/// by about step 9,000 and the other half, 400 queries, is the spare. `(asked in A, asked in B)`
/// from the opening's end to step 9,000, and the steps asked in that stretch's last 2,000.
fn repayment_split(by_visits: bool) -> ((u64, u64), u64) {
    let budget = AskBudget::new(0.1, 20)
        .opening_for(1_000)
        .starting_empty()
        .opening_at(0.5)
        .repaying(0.5);
    let mut rule = QueryRule::new(0.2, 4, UcbForm::Authors)
        .waking_after(1_000)
        .with_ceiling(budget)
        .opening_by_visits();
    if by_visits {
        rule = rule.repayment_by_visits();
    }
    let (mut asked, mut late) = ((0, 0), 0);
    for step in 0..9_000u64 {
        let g = if step % 4 == 3 { B } else { A };
        if rule.visit(g) {
            rule.record(g, 1.0, 0.0);
            if step < 1_000 {
                continue;
            }
            late += u64::from(step >= 7_000);
            if g == A {
                asked.0 += 1;
            } else {
                asked.1 += 1;
            }
        }
    }
    (asked, late)
}

#[test]
fn a_repayment_by_visits_spends_its_spare_where_the_learner_is() {
    // By visits: the spare's 5 % of A's 6,000 visits and of B's 2,000, spread over the stretch
    // (the debt is repaid a few steps before 9,000, when the ceiling's ranking asks a few more).
    let ((a, b), late) = repayment_split(true);
    assert!(
        (295..=300).contains(&a) && (98..=105).contains(&b),
        "{a}, {b}"
    );
    assert!((90..=110).contains(&late), "{late} in the last 2,000 steps");
    // Ranked, only the best-ranked state may ask the spare, and the score's count term makes
    // that the state with fewer answers: as much is spent, most of it in B.
    let ((a, b), _) = repayment_split(false);
    assert!(a + b >= 390, "the ranked spare is spent too: {a} + {b}");
    assert!(b > 2 * a, "{a}, {b}");
}

#[test]
fn a_waking_rule_asks_the_best_state_of_the_silence() {
    let (good, bad) = (AbstractState(20), AbstractState(21));
    let mut rule = QueryRule::new(0.1, 0, UcbForm::Authors).waking_after(10);
    frozen_history(&mut rule);
    rule.record(good, 1.0, 1.0);
    rule.record(good, 1.0, 1.0);
    rule.record(bad, 1.0, -1.0);
    rule.record(bad, 1.0, -1.0);
    for _ in 0..5 {
        assert!(
            !rule.visit(bad),
            "ranked among every answered state: not asked"
        );
    }
    for _ in 0..4 {
        assert!(!rule.visit(good));
    }
    // The tenth silent step: `bad` outranks `good` among the silence's states.
    assert!(
        !rule.visit(good),
        "k = 0: only the best ranked state of the silence asks"
    );
    assert!(rule.visit(bad));
}

#[test]
fn the_recent_rank_still_prefers_the_worse_predicted_of_the_visited_states() {
    let (good, bad) = (AbstractState(1), AbstractState(2));
    let mut rule = QueryRule::new(0.01, 0, UcbForm::Authors).ranked_among_recent(10);
    rule.record(good, 1.0, 0.9);
    rule.record(bad, 1.0, -1.0);
    rule.visit(good);
    assert!(
        rule.visit(bad),
        "the worse predicted state is the best ranked"
    );
    assert!(
        !rule.visit(good),
        "k = 0: only the best ranked recent state asks"
    );
    // Once `bad` has left the window, `good` is the best of what the learner visits.
    for _ in 0..10 {
        rule.visit(good);
    }
    assert!(rule.visit(good));
}

#[test]
fn a_ceiling_bounds_the_flood_of_the_first_states() {
    // With k + 1 or fewer states answered the authors' rule asks at every step.
    let (a, b) = (AbstractState(1), AbstractState(2));
    let mut authors = QueryRule::new(0.1, 2, UcbForm::Authors);
    let mut capped = QueryRule::new(0.1, 2, UcbForm::Authors)
        .ranked_among_recent(1_000)
        .with_ceiling(AskBudget::new(0.05, 20));
    let run = |rule: &mut QueryRule| {
        let (mut asked, mut pacing) = (0u64, AskPacing::default());
        for step in 0..20_000u64 {
            let g = if step % 7 < 4 { a } else { b };
            let ask = rule.visit(g);
            if ask {
                rule.record(g, 1.0, 0.5);
            }
            pacing.step(step, ask);
            asked += u64::from(ask);
        }
        (asked, pacing.longest_flood)
    };
    assert_eq!(run(&mut authors), (20_000, 20_000));
    let (asked, longest) = run(&mut capped);
    assert!(asked <= 1_020, "asked {asked} of 20000 under a 5 % ceiling");
    assert!(longest <= 21, "{longest} in a row");
}

#[test]
fn a_rule_with_window_and_ceiling_survives_a_serde_round_trip() {
    let mut rule = QueryRule::new(0.2, 4, UcbForm::Authors)
        .ranked_among_recent(50)
        .with_ceiling(AskBudget::new(0.05, 20))
        .waking_after(7);
    for g in 0..30 {
        if rule.visit(AbstractState(g % 7)) {
            rule.record(AbstractState(g % 7), 1.0, 0.0);
        }
    }
    let back: QueryRule = serde_json::from_str(&serde_json::to_string(&rule).unwrap()).unwrap();
    assert_eq!(back, rule);
    // A checkpoint of the authors' rule written before these fields existed still reads.
    let old = r#"{"c":0.2,"k":4,"form":"authors","total":0,"stats":{}}"#;
    let old: QueryRule = serde_json::from_str(old).unwrap();
    assert_eq!(old, QueryRule::new(0.2, 4, UcbForm::Authors));
}
