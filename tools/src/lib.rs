//! The relume command-line program's library side: the pieces its subcommands are built
//! from, kept in a library so that they can be tested without running the binary.

pub mod scenegen;
