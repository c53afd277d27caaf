"""Collision-free motion (OMPL) and task-level commands (pick, place, handover)."""
