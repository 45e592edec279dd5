//! Tests of the query rule's settings (`query_rule.rs`): the ceiling, its opening and
//! repayment, where they ask, and each refused by name.

use crate::guidance::evaluative_run::FeedbackCeiling;
use crate::guidance::feedback_schedule::EvaluativeMethod;
use crate::guidance::visit_share::OpeningPlacement;
use crate::settings::Settings;
use crate::sim::Task;

/// The ceiling `pairs` give `method` on `task`, or the error as a user reads it.
fn ceiling(
    task: Task,
    pairs: &[(&str, &str)],
    method: EvaluativeMethod,
) -> Result<Option<FeedbackCeiling>, String> {
    Settings::from_pairs(pairs.iter().copied())
        .and_then(|s| s.evaluative(task, method, 0))
        .map(|c| c.query_rule.ceiling)
        .map_err(|e| e.to_string())
}

#[test]
fn the_opening_is_a_setting_of_the_ceiling_2000_steps_for_dref() {
    let plain = Settings::default()
        .evaluative(Task::Placing, EvaluativeMethod::Dref, 0)
        .unwrap();
    let ceiling = plain.query_rule.ceiling.unwrap();
    assert_eq!(
        (ceiling.rate, ceiling.burst, ceiling.opening),
        (0.1, 20, 2000)
    );
    let closed = Settings::from_pairs([("feedback_opening", "0")])
        .unwrap()
        .evaluative(Task::Placing, EvaluativeMethod::Dref, 0)
        .unwrap();
    assert_eq!(closed.query_rule.ceiling.map(|c| c.opening), Some(0));
    // A ceiling set on the authors' rule opens only when asked to.
    let capped = Settings::from_pairs([("max_feedback_rate", "0.1")])
        .unwrap()
        .evaluative(Task::Placing, EvaluativeMethod::DrefAuthors, 0)
        .unwrap();
    assert_eq!(capped.query_rule.ceiling.map(|c| c.opening), Some(0));
    // The authors' rule has no ceiling to open: refused by name, unless it is 0.
    let no_ceiling = Settings::from_pairs([("feedback_opening", "2000")])
        .unwrap()
        .evaluative(Task::Placing, EvaluativeMethod::DrefAuthors, 0)
        .unwrap_err()
        .to_string();
    assert!(no_ceiling.contains("feedback_opening"), "{no_ceiling}");
    assert!(no_ceiling.contains("no ceiling"), "{no_ceiling}");
    assert!(
        Settings::from_pairs([("feedback_opening", "0")])
            .unwrap()
            .evaluative(Task::Placing, EvaluativeMethod::DrefAuthors, 0)
            .is_ok()
    );
    let not_a_number = Settings::from_pairs([("feedback_opening", "-3")])
        .unwrap_err()
        .to_string();
    assert!(not_a_number.contains("feedback_opening"), "{not_a_number}");
}

#[test]
fn the_openings_accounting_is_two_settings_of_the_ceiling_on_for_dref_only() {
    let rule = |pairs: &[(&str, &str)], method| ceiling(Task::Reaching, pairs, method);
    let product = rule(&[], EvaluativeMethod::Dref).unwrap().unwrap();
    assert_eq!((product.start_empty, product.repay_share), (true, 0.9));
    let off = rule(
        &[
            ("feedback_start_empty", "false"),
            ("opening_repay_share", "1"),
        ],
        EvaluativeMethod::Dref,
    )
    .unwrap()
    .unwrap();
    assert_eq!((off.start_empty, off.repay_share), (false, 1.0));
    assert_eq!((off.rate, off.burst, off.opening), (0.1, 20, 2000));
    // A ceiling set on the authors' rule has neither unless asked.
    let capped = rule(
        &[("max_feedback_rate", "0.1")],
        EvaluativeMethod::DrefAuthors,
    );
    let capped = capped.unwrap().unwrap();
    assert_eq!((capped.start_empty, capped.repay_share), (false, 1.0));
    let set = rule(
        &[
            ("max_feedback_rate", "0.1"),
            ("feedback_opening", "2000"),
            ("feedback_start_empty", "true"),
            ("opening_repay_share", "0.5"),
        ],
        EvaluativeMethod::DrefAuthors,
    );
    let set = set.unwrap().unwrap();
    assert_eq!((set.start_empty, set.repay_share), (true, 0.5));
    // A repayment without an opening would be inert: refused by name.
    let no_opening = rule(
        &[("max_feedback_rate", "0.1"), ("opening_repay_share", "0.5")],
        EvaluativeMethod::DrefAuthors,
    )
    .unwrap_err();
    assert!(
        no_opening.contains("opening_repay_share") && no_opening.contains("no opening to repay"),
        "{no_opening}"
    );
    // Out of range, or with no ceiling to hold them: refused by name.
    for (pairs, name, words) in [
        (
            vec![("opening_repay_share", "0")],
            "opening_repay_share",
            "(0, 1]",
        ),
        (
            vec![("opening_repay_share", "1.5")],
            "opening_repay_share",
            "(0, 1]",
        ),
        (
            vec![("feedback_start_empty", "yes")],
            "feedback_start_empty",
            "",
        ),
    ] {
        let e = rule(&pairs, EvaluativeMethod::Dref).unwrap_err();
        assert!(e.contains(name) && e.contains(words), "{e}");
    }
    for name in ["feedback_start_empty", "opening_repay_share"] {
        let value = if name == "feedback_start_empty" {
            "true"
        } else {
            "0.9"
        };
        let e = rule(&[(name, value)], EvaluativeMethod::DrefAuthors).unwrap_err();
        assert!(e.contains(name) && e.contains("no ceiling"), "{e}");
    }
    // Their "off" values are accepted on the authors' rule, which has no ceiling.
    let off = [
        ("feedback_start_empty", "false"),
        ("opening_repay_share", "1"),
    ];
    assert_eq!(rule(&off, EvaluativeMethod::DrefAuthors), Ok(None));
}

#[test]
fn a_paced_opening_needs_an_opening_and_a_share_of_its_steps() {
    // Placing: its product opening is unpaced (Lunar Lander's is paced and placed by visits).
    let rule = |pairs: &[(&str, &str)], method| ceiling(Task::Placing, pairs, method);
    let product = rule(&[], EvaluativeMethod::Dref).unwrap().unwrap();
    assert_eq!(product.opening_rate, None, "off by default");
    let paced = rule(
        &[("feedback_opening", "15000"), ("opening_rate", "0.33")],
        EvaluativeMethod::Dref,
    );
    let paced = paced.unwrap().unwrap();
    assert_eq!((paced.opening, paced.opening_rate), (15_000, Some(0.33)));
    let zero = rule(&[("opening_rate", "0")], EvaluativeMethod::Dref);
    assert_eq!(zero.unwrap().unwrap().opening_rate, None);
    assert_eq!(
        rule(&[("opening_rate", "0")], EvaluativeMethod::DrefAuthors),
        Ok(None),
        "its off value on a rule without a ceiling"
    );
    for (pairs, method, words) in [
        (
            vec![("opening_rate", "1.5")],
            EvaluativeMethod::Dref,
            "(0, 1]",
        ),
        (
            vec![("opening_rate", "-0.1")],
            EvaluativeMethod::Dref,
            "(0, 1]",
        ),
        (
            vec![("opening_rate", "0.3"), ("feedback_opening", "0")],
            EvaluativeMethod::Dref,
            "no opening",
        ),
        (
            vec![("opening_rate", "0.3")],
            EvaluativeMethod::DrefAuthors,
            "no ceiling",
        ),
    ] {
        let e = rule(&pairs, method).unwrap_err();
        assert!(e.contains("opening_rate") && e.contains(words), "{e}");
    }
}

#[test]
fn a_placement_by_visits_needs_a_paced_opening() {
    // Placing: its product opening is unpaced (Lunar Lander's is paced and placed by visits).
    let rule = |pairs: &[(&str, &str)], method| ceiling(Task::Placing, pairs, method);
    let product = rule(&[], EvaluativeMethod::Dref).unwrap().unwrap();
    assert_eq!(product.opening_placement, OpeningPlacement::Ranked);
    let paced = [
        ("feedback_opening", "30000"),
        ("opening_rate", "0.45"),
        ("opening_placement", "by_visits"),
    ];
    let paced = rule(&paced, EvaluativeMethod::Dref).unwrap().unwrap();
    assert_eq!(paced.opening_placement, OpeningPlacement::ByVisits);
    assert_eq!(
        rule(
            &[("opening_placement", "ranked")],
            EvaluativeMethod::DrefAuthors
        ),
        Ok(None),
        "its off value on a rule without a ceiling"
    );
    for (pairs, method, words) in [
        (
            vec![("opening_placement", "by_visits")],
            EvaluativeMethod::Dref,
            "set opening_rate",
        ),
        (
            vec![("opening_placement", "by_visits")],
            EvaluativeMethod::DrefAuthors,
            "no ceiling",
        ),
        (
            vec![("opening_placement", "at_random")],
            EvaluativeMethod::Dref,
            "by_visits",
        ),
    ] {
        let e = rule(&pairs, method).unwrap_err();
        assert!(e.contains("opening_placement") && e.contains(words), "{e}");
    }
}

#[test]
fn a_repayment_by_visits_needs_an_opening_repaid_in_part() {
    let rule = |pairs: &[(&str, &str)], method| ceiling(Task::LunarLander, pairs, method);
    let product = rule(&[], EvaluativeMethod::Dref).unwrap().unwrap();
    assert_eq!(product.repayment_placement, OpeningPlacement::Ranked);
    // The product's opening (2,000 steps, repaid from 90 %) leaves a spare to place.
    let placed = [("repayment_placement", "by_visits")];
    let placed = rule(&placed, EvaluativeMethod::Dref).unwrap().unwrap();
    assert_eq!(placed.repayment_placement, OpeningPlacement::ByVisits);
    assert_eq!(
        rule(
            &[("repayment_placement", "ranked")],
            EvaluativeMethod::DrefAuthors
        ),
        Ok(None),
        "its off value on a rule without a ceiling"
    );
    for (pairs, method, words) in [
        (
            vec![
                ("opening_repay_share", "1"),
                ("repayment_placement", "by_visits"),
            ],
            EvaluativeMethod::Dref,
            "opening_repay_share below 1",
        ),
        (
            vec![
                ("feedback_opening", "0"),
                ("repayment_placement", "by_visits"),
            ],
            EvaluativeMethod::Dref,
            "set feedback_opening",
        ),
        (
            vec![("repayment_placement", "by_visits")],
            EvaluativeMethod::DrefAuthors,
            "no ceiling",
        ),
    ] {
        let e = rule(&pairs, method).unwrap_err();
        assert!(
            e.contains("repayment_placement") && e.contains(words),
            "{e}"
        );
    }
}

#[test]
fn unpacing_lunar_landers_opening_takes_its_placement_with_it() {
    // Lunar Lander's product opening is paced and placed by visits: set to no pace, the config
    // carries no placement of a pace that does not run, and a placement or taper set beside it
    // is refused by name.
    let rule = |pairs: &[(&str, &str)]| ceiling(Task::LunarLander, pairs, EvaluativeMethod::Dref);
    let product = rule(&[]).unwrap().unwrap();
    assert_eq!(product.opening_placement, OpeningPlacement::ByVisits);
    let unpaced = rule(&[("opening_rate", "0")]).unwrap().unwrap();
    assert_eq!(
        (
            unpaced.opening_rate,
            unpaced.opening_placement,
            unpaced.opening_taper
        ),
        (None, OpeningPlacement::Ranked, false)
    );
    assert_eq!(unpaced.opening, product.opening, "the opening itself stays");
    for (pairs, key) in [
        (
            [("opening_rate", "0"), ("opening_placement", "by_visits")],
            "opening_placement",
        ),
        (
            [("opening_rate", "0"), ("opening_taper", "true")],
            "opening_taper",
        ),
    ] {
        let e = rule(&pairs).unwrap_err();
        assert!(e.contains(key) && e.contains("set opening_rate"), "{e}");
    }
}

#[test]
fn a_taper_needs_a_paced_opening() {
    let rule = |pairs: &[(&str, &str)], method| ceiling(Task::LunarLander, pairs, method);
    let product = rule(&[], EvaluativeMethod::Dref).unwrap().unwrap();
    assert!(!product.opening_taper, "the product's opening is flat");
    // Lunar Lander's product opening is paced: doubled and tapered, it spends the same.
    let tapered = [("feedback_opening", "60000"), ("opening_taper", "true")];
    let tapered = rule(&tapered, EvaluativeMethod::Dref).unwrap().unwrap();
    assert!(tapered.opening_taper);
    assert_eq!(
        (tapered.opening, tapered.opening_rate),
        (60_000, Some(0.45))
    );
    let budget = |c: FeedbackCeiling| {
        let mut b = c.budget();
        let mut earned = 0.0;
        for _ in 0..c.opening {
            b.tick();
            earned += b.opening_rate_now().unwrap();
        }
        earned
    };
    let flat = budget(product);
    assert!((flat - 13_500.0).abs() < 1e-6, "{flat}");
    assert!((budget(tapered) - 13_500.2).abs() < 0.1, "the same answers");
    assert_eq!(
        rule(&[("opening_taper", "false")], EvaluativeMethod::DrefAuthors),
        Ok(None),
        "its off value on a rule without a ceiling"
    );
    for (pairs, task, method, words) in [
        (
            vec![("opening_taper", "true")],
            Task::Placing,
            EvaluativeMethod::Dref,
            "set opening_rate",
        ),
        (
            vec![("opening_taper", "true")],
            Task::LunarLander,
            EvaluativeMethod::DrefAuthors,
            "no ceiling",
        ),
        (
            vec![("opening_taper", "yes please")],
            Task::LunarLander,
            EvaluativeMethod::Dref,
            "opening_taper",
        ),
    ] {
        let e = ceiling(task, &pairs, method).unwrap_err();
        assert!(e.contains("opening_taper") && e.contains(words), "{e}");
    }
}

#[test]
fn closing_an_opening_leaves_nothing_of_it_in_the_config() {
    // Lunar Lander's product opening is paced, placed by visits and repaid from 90 %: closed,
    // none of that is left to be read as if the opening ran.
    let closed = ceiling(
        Task::LunarLander,
        &[("feedback_opening", "0")],
        EvaluativeMethod::Dref,
    )
    .unwrap()
    .unwrap();
    let product = ceiling(Task::LunarLander, &[], EvaluativeMethod::Dref)
        .unwrap()
        .unwrap();
    assert_eq!(
        closed,
        FeedbackCeiling {
            opening: 0,
            repay_share: 1.0,
            opening_rate: None,
            opening_placement: OpeningPlacement::Ranked,
            ..product
        },
        "the rate, burst and empty start stay"
    );
    assert!(closed.start_empty && closed.rate == 0.1);
    // Set again after the close, each is refused by name: there is no opening to shape.
    for (key, value, words) in [
        ("opening_rate", "0.45", "no opening to pace"),
        ("opening_repay_share", "0.9", "no opening to repay"),
        ("opening_placement", "by_visits", "set opening_rate"),
    ] {
        let e = ceiling(
            Task::LunarLander,
            &[("feedback_opening", "0"), (key, value)],
            EvaluativeMethod::Dref,
        )
        .unwrap_err();
        assert!(e.contains(key) && e.contains(words), "{e}");
    }
}
