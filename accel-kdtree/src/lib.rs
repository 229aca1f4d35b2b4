//! SAH kD-tree (to come, issue 5): splits chosen by the surface area
//! heuristic with the O(n log n) event-sweep build of Wald & Havran (2006).
