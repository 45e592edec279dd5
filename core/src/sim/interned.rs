//! Names that arrive at run time but live as long as the program: an environment in another
//! process declares its id, its observation and action names and its predicates, and the
//! rest of the code holds such names as `&'static str` (the built-in tasks' are constants).
//!
//! Each distinct text is leaked once and shared after that, so resuming a session or reconnecting
//! to the same env costs nothing more; what leaks is bounded by the distinct names the
//! researcher's environments declare (the protocol caps their number and length).

use std::collections::HashSet;
use std::sync::{Mutex, OnceLock};

/// The one `&'static str` with this text.
pub fn intern(text: &str) -> &'static str {
    static NAMES: OnceLock<Mutex<HashSet<&'static str>>> = OnceLock::new();
    let mut names = NAMES
        .get_or_init(Default::default)
        .lock()
        .unwrap_or_else(|e| e.into_inner());
    if let Some(&name) = names.get(text) {
        return name;
    }
    let name: &'static str = Box::leak(text.to_owned().into_boxed_str());
    names.insert(name);
    name
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_same_text_is_the_same_str() {
        let a = intern("gripper above hoop");
        let b = intern(&String::from("gripper above hoop"));
        assert!(std::ptr::eq(a, b));
        assert_ne!(intern("x"), intern("y"));
    }
}
