//! What the operating system can tell about this process: CPU time of
//! threads and children ([`cputime`]), resident memory ([`memory`]), and
//! the memory it may use, which every size a user gives is checked against
//! ([`budget`]). Linux `/proc` only; every reading is `None` elsewhere.

pub mod budget;
pub mod cputime;
pub mod memory;
