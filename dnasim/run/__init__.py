"""Stage 4: ``simulate(system, solver, sinks) -> Results``: backends, sinks, the
results on disk, and what ``dnasim run`` does between loading a plant and its summary."""
