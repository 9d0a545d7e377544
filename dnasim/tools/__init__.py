"""Work on results and plants beside a run: plots, the report and schematic, sweeps,
linearisation, the design-point table, the component reference."""
