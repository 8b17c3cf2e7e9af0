"""The convex programs: the conic program shape, the formulations' builders and the source rows."""
