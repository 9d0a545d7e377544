"""The component contract (``dnasim.model.component``): ``Component``, its ports,
parameters, variables, equations (declared once with names, dependencies and units) and
switches. Components depend on this and on media; nothing here knows plants or solvers."""
