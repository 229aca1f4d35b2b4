//! Octree of nested uniform grids (to come, issue 4): a cell of an
//! `accel-grid` grid that holds too many references becomes a grid of its own,
//! so dense clusters get fine cells while empty space stays coarse.
