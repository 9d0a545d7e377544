"""Shared sub-models of the component library: flow channels of finite volumes, wall
heat conduction and storage, valve characteristics, tube geometry and heat-transfer laws.
Not components themselves; components build on them. (The regularised physics every
component shares, upwinding included, is ``dnasim.model.physics``.)"""
