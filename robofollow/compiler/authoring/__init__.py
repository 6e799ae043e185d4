"""The spec language a task author writes: .rf files -> the typed, validated benchmark.

Syntax and parse of the files, their checks with located errors, layouts posed on the table
(footprints, recolours), and the split rules as written. Imports the scene and language rooms;
never the planner.
"""
