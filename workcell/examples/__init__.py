"""Example builders: the thesis's solids (and, as they land, its workcells)."""
