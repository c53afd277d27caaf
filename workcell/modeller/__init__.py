"""The solid modeller (thesis ch. 2-3): surfaces, the datamodel, solids, sweeps, booleans,
world coordinates, geometric properties, save/load."""
