//! The `multires` command-line tool.

fn main() {
    println!("multires");
}
