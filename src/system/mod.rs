//! What the operating system can tell about this process: CPU time of
//! threads and children ([`cputime`]) and resident memory ([`memory`]).
//! Linux `/proc` only; every reading is `None` elsewhere.

pub mod cputime;
pub mod memory;
