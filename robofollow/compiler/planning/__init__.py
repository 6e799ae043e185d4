"""From a grounded behaviour to what is scored and what the expert does: the scoring profile,
the goal DAG (goals.py), routes, expert plans and motions, and the feasibility check that
refuses what the expert cannot perform.

Imports the scene and language rooms; never the spec language (authoring).
"""
