//! Debian packages the tests need and install where missing (as `bash tests/run.sh` does
//! before the suite): PostgreSQL, nginx.

use std::process::Command;

/// Whether this process runs as root (and so may install packages).
pub fn is_root() -> bool {
    Command::new("id")
        .arg("-u")
        .output()
        .is_ok_and(|o| String::from_utf8_lossy(&o.stdout).trim() == "0")
}

/// `apt-get install` `package`, as root; panics when it fails, or when not root with `hint`
/// (what to do instead).
pub fn install(package: &str, hint: &str) {
    assert!(
        is_root(),
        "the tests need Debian's {package}, which is not installed. Install it with `sudo \
         apt-get install -y {package}` (`bash tests/run.sh` installs what is missing, then runs \
         every test){hint}"
    );
    eprintln!("installing Debian's {package} (apt-get)");
    let apt = |args: &[&str]| {
        let status = Command::new("apt-get")
            .args(args)
            .env("DEBIAN_FRONTEND", "noninteractive")
            .status()
            .expect("running apt-get");
        assert!(status.success(), "apt-get {args:?} failed");
    };
    apt(&["update", "-qq"]);
    apt(&["install", "-y", "-qq", package]);
}
