//! # agent: the ivlmap language layer (work in progress)
