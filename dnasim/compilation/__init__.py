"""Stage 2: ``compile(plant) -> System``, the one semi-explicit index-1 DAE over
plant-wide arrays, with its structural checks and the plant limits as a switch."""
