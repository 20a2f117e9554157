//! The `aprt` command line.

fn main() {
    println!("aprt");
}
