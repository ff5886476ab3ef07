"""Closed-chain dynamics: trajectories on the closure manifold, inverse and forward dynamics, task space."""
