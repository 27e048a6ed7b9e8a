"""plan-deal's algorithm: the SA plan's pieces dealt to N agents."""
