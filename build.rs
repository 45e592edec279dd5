fn main() {
    // sqlx::migrate! embeds migrations/: rebuild when they change.
    println!("cargo:rerun-if-changed=migrations");
    // shipped.rs embeds web/ and models/ in every build: rebuild when a file in them changes or
    // is added (include_bytes! alone would not see a new file).
    println!("cargo:rerun-if-changed=web");
    println!("cargo:rerun-if-changed=models");
}
