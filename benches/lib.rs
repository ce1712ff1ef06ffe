//! strata's criterion benches live beside this file (`cargo bench -p
//! strata-benches --bench kernels`); the library is empty.
