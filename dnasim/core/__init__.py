"""Stage 0, shared by every stage: errors, units and parameter values, time functions,
signal handling, BLAS threads. Imports nothing else of dnasim."""
