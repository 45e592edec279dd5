//! Tests of the ceiling on how often DREF asks (`ask_budget.rs`).

use super::super::ask_pacing::AskPacing;
use super::*;

/// Asks on every step it may for `steps` steps, ticking first as the rule does; the count.
fn ask_whenever_allowed(budget: &mut AskBudget, steps: u64) -> u64 {
    let mut asked = 0;
    for _ in 0..steps {
        budget.tick();
        if budget.can_ask() {
            budget.spend(1.0);
            asked += 1;
        }
    }
    asked
}

/// As [`ask_whenever_allowed`], with the longest stretch of consecutive asked steps.
fn ask_whenever_allowed_streaks(budget: &mut AskBudget, steps: u64) -> (u64, u64) {
    let (mut asked, mut pacing) = (0, AskPacing::default());
    for step in 0..steps {
        let ask = ask_whenever_allowed(budget, 1) == 1;
        pacing.step(step, ask);
        asked += u64::from(ask);
    }
    (asked, pacing.longest_flood)
}

#[test]
fn an_opening_asks_on_every_step_then_repays_before_asking_again() {
    let mut budget = AskBudget::new(0.1, 20).opening_for(2_000);
    budget.tick();
    assert_eq!(
        budget.ranks_allowed(4),
        4,
        "the opening lets every rank ask"
    );
    budget.spend(1.0);
    assert_eq!(1 + ask_whenever_allowed(&mut budget, 1_999), 2_000);
    // 20 held and 0.1 a step earned over the 1,999 steps after the first: 1,780.1
    // borrowed, and nothing more asked until earnings repay them (17,811 steps).
    assert!((budget.tokens + 1_780.1).abs() < 1e-6, "{}", budget.tokens);
    budget.tick();
    assert!(!budget.can_ask(), "the step after the opening");
    assert_eq!(budget.ranks_allowed(4), 0);
    assert_eq!(ask_whenever_allowed(&mut budget, 17_799), 0);
    // Over the whole run the ceiling holds: at most 10 % of the steps plus the burst.
    let total = 2_000 + ask_whenever_allowed(&mut budget, 100_000 - 2_000 - 17_800);
    assert!(total <= 10_000 + 20, "{total}");
    assert!(total >= 9_990, "{total}");
}

#[test]
fn an_empty_start_keeps_a_greedy_run_within_its_rate_at_every_step_after_repaying() {
    for (start_empty, limit) in [(false, 10_020), (true, 10_000)] {
        let mut budget = AskBudget::new(0.1, 20).opening_for(2_000);
        if start_empty {
            budget = budget.starting_empty();
        }
        let mut asked = ask_whenever_allowed(&mut budget, 2_000);
        assert_eq!(asked, 2_000);
        let mut worst = 0.0f64;
        for step in 2_001..=100_000u64 {
            asked += ask_whenever_allowed(&mut budget, 1);
            if step > 20_100 {
                worst = worst.max(asked as f64 - 0.1 * step as f64);
            }
        }
        assert!(asked <= limit, "start empty {start_empty}: {asked}");
        assert!(asked >= limit - 10, "start empty {start_empty}: {asked}");
        // A full bucket runs up to its burst over 10 % of the steps so far; an empty one
        // never passes 10 % once the opening is repaid.
        let most = if start_empty { 0.0 } else { 20.0 };
        assert!(worst <= most + 1e-9, "start empty {start_empty}: {worst}");
        assert!(worst > most - 1.5, "start empty {start_empty}: {worst}");
    }
}

#[test]
fn repaying_from_a_share_asks_the_rest_while_it_repays_and_keeps_the_total() {
    let mut budget = AskBudget::new(0.1, 20)
        .opening_for(2_000)
        .starting_empty()
        .repaying(0.9);
    assert_eq!(ask_whenever_allowed(&mut budget, 2_000), 2_000);
    // 1,800 borrowed (2,000 asked, 200 earned), repaid at 0.09 a step: 20,000 steps, in
    // which the other 0.01 a step is askable: one query every 100 steps, for the best state.
    let (mut asked, mut silent, mut longest_silence) = (0u64, 0u64, 0u64);
    for _ in 0..19_990 {
        budget.tick();
        assert!(budget.tokens < 0.0, "still repaying");
        if budget.can_ask() {
            assert_eq!(budget.ranks_allowed(4), 0, "only the best-ranked state");
            budget.spend(-1.0);
            asked += 1;
            silent = 0;
        } else {
            silent += 1;
            longest_silence = longest_silence.max(silent);
        }
    }
    assert!((198..=200).contains(&asked), "{asked}");
    assert!(longest_silence <= 101, "{longest_silence}");
    // Once repaid, the plain ceiling; over the run at most 10 % of the steps.
    let total = 2_000 + asked + ask_whenever_allowed(&mut budget, 100_000 - 2_000 - 19_990);
    assert!((9_990..=10_000).contains(&total), "{total}");
    assert!(budget.tokens >= 0.0 && budget.spare == 0.0);
}

#[test]
fn repaying_in_full_is_the_opening_as_before_bit_for_bit() {
    let mut before = AskBudget::new(0.1, 20).opening_for(2_000);
    let mut whole = AskBudget::new(0.1, 20).opening_for(2_000).repaying(1.0);
    for step in 0..30_000u32 {
        before.tick();
        whole.tick();
        assert_eq!(before.can_ask(), whole.can_ask());
        if before.can_ask() && step % 2 == 0 {
            before.spend(1.0);
            whole.spend(1.0);
        }
        assert_eq!(before.tokens.to_bits(), whole.tokens.to_bits());
    }
    assert_eq!(before, whole);
}

#[test]
fn a_paced_opening_asks_its_share_then_repays_within_the_runs_ceiling() {
    let mut budget = AskBudget::new(0.1, 20)
        .opening_for(15_000)
        .starting_empty()
        .repaying(0.9)
        .opening_at(1.0 / 3.0);
    let (asked, longest) = ask_whenever_allowed_streaks(&mut budget, 15_000);
    assert!(budget.in_paced_opening(), "its last step");
    // A third of the steps from a bucket that starts empty: no flood at all.
    assert!((4_990..=5_000).contains(&asked), "{asked}");
    assert_eq!(longest, 1, "one query, then two steps earning the next");
    // 5,000 asked against 1,500 earned: 3,500 repaid at 0.09 a step (38,889 steps), after
    // which the run is within 10 % of its steps.
    assert!((budget.tokens + 3_500.0).abs() < 5.0, "{}", budget.tokens);
    let after = ask_whenever_allowed(&mut budget, 150_000 - 15_000);
    assert!(!budget.in_paced_opening());
    assert!(
        (14_990..=15_000).contains(&(asked + after)),
        "{}",
        asked + after
    );
}

#[test]
fn a_tapered_opening_asks_half_as_many_thinning_out_to_its_end() {
    let mut budget = AskBudget::new(0.1, 20)
        .opening_for(60_000)
        .starting_empty()
        .repaying(0.9)
        .opening_at(0.45)
        .tapering();
    // Step i of 60,000 earns 0.45 * (60,001 - i) / 60,000: 10,125.1 over the first half,
    // 3,375.1 over the second, 13,500.2 in all (the flat opening's over 30,000 steps).
    let first_half = ask_whenever_allowed(&mut budget, 30_000);
    let second_half = ask_whenever_allowed(&mut budget, 29_000);
    assert!((10_124..=10_125).contains(&first_half), "{first_half}");
    let last = ask_whenever_allowed(&mut budget, 1_000);
    assert!(budget.in_tapered_opening(), "its last step");
    // The last 1,000 steps earn 0.45 * 500.5 * 1,000 / 60,000 = 3.75.
    assert!((3..=5).contains(&last), "{last}");
    let opening = first_half + second_half + last;
    assert!((13_499..=13_500).contains(&opening), "{opening}");
    // 13,500 asked against 6,000 earned: 7,500 repaid at 0.09 a step, and the run's total is
    // within 10 % of its steps.
    let after = ask_whenever_allowed(&mut budget, 150_000 - 60_000);
    assert!(!budget.in_tapered_opening());
    assert!(
        (14_990..=15_000).contains(&(opening + after)),
        "{}",
        opening + after
    );
    // Tapering an opening that is not paced leaves the bucket as it was.
    let unpaced = AskBudget::new(0.1, 20).opening_for(1_000);
    assert_eq!(unpaced.clone().tapering(), unpaced);
}

#[test]
fn a_paced_opening_admits_more_ranks_as_its_bucket_fills() {
    let mut budget = AskBudget::new(0.1, 21).opening_for(1_000).opening_at(0.5);
    budget.tick();
    assert!(!budget.can_ask(), "its own bucket starts empty");
    budget.tick();
    assert!(budget.can_ask());
    assert_eq!(
        budget.ranks_allowed(60),
        0,
        "one query: the best state only"
    );
    for _ in 0..40 {
        budget.tick();
    }
    assert_eq!(budget.ranks_allowed(60), 60, "full: every rank");
    // Ticks outside the opening leave the opening's bucket alone.
    let mut done = AskBudget::new(0.1, 20).opening_for(1).opening_at(0.5);
    done.tick();
    done.tick();
    assert!(!done.in_paced_opening());
    assert_eq!(done.opening_bucket.map(|b| b.tokens), Some(0.5));
}

#[test]
fn no_opening_is_the_plain_bucket_bit_for_bit() {
    let mut plain = AskBudget::new(0.1, 20);
    let mut opened = AskBudget::new(0.1, 20).opening_for(0);
    for step in 0..5_000u32 {
        plain.tick();
        opened.tick();
        assert_eq!(plain.can_ask(), opened.can_ask());
        if plain.can_ask() && step % 3 == 0 {
            plain.spend(1.0);
            opened.spend(1.0);
        }
        assert_eq!(plain.tokens.to_bits(), opened.tokens.to_bits());
    }
    assert_eq!(plain, opened);
}

#[test]
fn asks_at_most_its_rate_and_its_burst_in_a_row() {
    let mut budget = AskBudget::new(0.05, 20);
    let (asked, longest) = ask_whenever_allowed_streaks(&mut budget, 100_000);
    // A greedy asker gets the full bucket, then one query every 20 steps.
    assert!((5_000..=5_020).contains(&asked), "asked {asked}");
    assert!((20..=22).contains(&longest), "longest streak {longest}");
}

#[test]
fn a_scarce_budget_admits_only_the_best_ranked_state() {
    let mut budget = AskBudget::new(0.1, 11);
    assert_eq!(
        budget.ranks_allowed(4),
        4,
        "a full bucket admits the top k + 1"
    );
    for _ in 0..10 {
        budget.spend(-1.0);
    }
    assert!(budget.can_ask());
    assert_eq!(
        budget.ranks_allowed(4),
        0,
        "the last token goes to the best state"
    );
    budget.spend(-1.0);
    assert!(!budget.can_ask());
    // A query's worth again after 1 / rate steps (one more for rounding of 0.1).
    for _ in 0..9 {
        budget.tick();
    }
    assert!(!budget.can_ask());
    budget.tick();
    budget.tick();
    assert!(budget.can_ask());
}

#[test]
fn an_answer_driven_rate_runs_from_the_floor_to_the_ceiling() {
    let mut budget = AskBudget::new(0.1, 20).following_answers(0.02);
    assert_eq!(budget.current_rate(), 0.1, "the ceiling before any answer");
    for _ in 0..RATE_ANSWERS {
        budget.spend(1.0);
    }
    assert!(
        (budget.current_rate() - 0.02).abs() < 1e-12,
        "all good: the floor"
    );
    for _ in 0..RATE_ANSWERS / 2 {
        budget.spend(-1.0);
    }
    assert!(
        (budget.current_rate() - 0.06).abs() < 1e-12,
        "half bad: half way"
    );
    for _ in 0..RATE_ANSWERS {
        budget.spend(-1.0);
    }
    assert!(
        (budget.current_rate() - 0.1).abs() < 1e-12,
        "all bad: the ceiling"
    );
    // "No feedback" (0) counts as not bad; a fixed bucket ignores answers.
    let mut fixed = AskBudget::new(0.05, 20);
    fixed.spend(-1.0);
    assert_eq!(fixed.current_rate(), 0.05);
}
