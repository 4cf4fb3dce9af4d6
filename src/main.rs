//! The `raylab` command line: run, render, verify, scenes.

fn main() {
    println!("raylab");
}
