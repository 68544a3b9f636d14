"""Contact between rods: the law, the broad phase, the energy term, the step bound, the report."""
