//! What the operating system can tell about this process: CPU time of
//! threads and children ([`cputime`]), resident memory ([`memory`]), the
//! wall time of a phase's named steps ([`steps`]), and the memory it may
//! use, which every size a user gives is checked against ([`budget`]). Linux `/proc` only; every reading is `None` elsewhere.

pub mod budget;
pub mod cputime;
pub mod memory;
pub mod steps;
