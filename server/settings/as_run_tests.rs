//! Tests of the as-run profile (issue 33): the constants it sets per task, and each of its
//! switches checked alone.

use super::*;
use crate::guidance::evaluative_run::{GraphAtEpisodeEnd, TimeLimitEnd};
use crate::scene_graph::SceneGraph;

#[test]
fn the_as_run_profile_sets_each_tasks_published_constants() {
    let as_run = Settings::from_pairs([("profile", "as-run")]).unwrap();
    let authors = |task| {
        as_run
            .evaluative(task, EvaluativeMethod::DrefAuthors, 0)
            .unwrap()
    };
    let ll = authors(Task::LunarLander);
    assert_eq!((ll.query_rule.c, ll.query_rule.k), (0.2, 50));
    assert_eq!(ll.oracle.alpha0, 0.99);
    assert_eq!(
        ll.scene_graph,
        SceneGraph::LunarLander {
            side_engines_on_a0: true
        }
    );
    assert_eq!(ll.graph_at_episode_end, GraphAtEpisodeEnd::Reset);
    assert_eq!(ll.time_limit, TimeLimitEnd::Truncation);
    let reaching = authors(Task::Reaching);
    assert_eq!((reaching.query_rule.c, reaching.query_rule.k), (0.1, 3));
    assert_eq!(reaching.oracle.action_scale, 0.1);
    assert_eq!(reaching.time_limit, TimeLimitEnd::Terminal);
    let placing = authors(Task::Placing);
    assert_eq!(placing.scene_graph, SceneGraph::PlacingAsRun);
    assert_eq!((placing.query_rule.c, placing.query_rule.k), (0.2, 4));
    assert_eq!(placing.time_limit, TimeLimitEnd::Terminal);
    // The head is untouched without the profile, and a given setting beats the profile's.
    let head = Settings::default()
        .evaluative(Task::LunarLander, EvaluativeMethod::DrefAuthors, 0)
        .unwrap();
    assert_eq!((head.query_rule.k, head.oracle.alpha0), (60, 0.999));
    assert_eq!(head.graph_at_episode_end, GraphAtEpisodeEnd::Step);
    let given = |pairs: &[(&str, &str)], task| {
        Settings::from_pairs(pairs.iter().copied())
            .unwrap()
            .evaluative(task, EvaluativeMethod::DrefAuthors, 0)
            .unwrap()
    };
    let k60 = given(&[("profile", "as-run"), ("k", "60")], Task::LunarLander);
    assert_eq!((k60.query_rule.k, k60.oracle.alpha0), (60, 0.99));
    let head_graph = given(
        &[("profile", "as-run"), ("scene_graph", "head")],
        Task::Placing,
    );
    assert_eq!(head_graph.scene_graph, SceneGraph::Placing);
    assert_eq!(head_graph.time_limit, TimeLimitEnd::Terminal);
}

#[test]
fn as_run_switches_are_checked_one_by_one() {
    let bad = |pairs: &[(&str, &str)], task| {
        Settings::from_pairs(pairs.iter().copied())
            .and_then(|s| s.evaluative(task, EvaluativeMethod::DrefAuthors, 0))
            .unwrap_err()
            .to_string()
    };
    assert!(bad(&[("oracle_alpha0", "1.5")], Task::Reaching).contains("oracle_alpha0"));
    assert!(bad(&[("oracle_action_scale", "0")], Task::Reaching).contains("oracle_action_scale"));
    assert!(bad(&[("scene_graph", "as-run")], Task::Reaching).contains("placing only"));
    assert!(bad(&[("time_limit", "sometimes")], Task::Reaching).contains("time_limit"));
    assert!(bad(&[("profile", "as-ran")], Task::Reaching).contains("profile"));
    let one = Settings::from_pairs([("scene_graph", "as-run"), ("graph_at_episode_end", "reset")])
        .unwrap()
        .evaluative(Task::Placing, EvaluativeMethod::Sac, 0)
        .unwrap();
    assert_eq!(one.scene_graph, SceneGraph::PlacingAsRun);
    assert_eq!(one.graph_at_episode_end, GraphAtEpisodeEnd::Reset);
    // The preference methods refuse the oracle's and the learner's switches.
    let pref = Settings::from_pairs([("time_limit", "terminal")])
        .unwrap()
        .preference(Task::Placing, QueryMethod::Drpl, 0)
        .unwrap_err()
        .to_string();
    assert!(pref.contains("time_limit"), "{pref}");
}
