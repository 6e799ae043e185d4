"""A scene as data and as geometry: the typed benchmark (spec.py), the workspace, a layout's
bodies and relations (world.py), what a policy sees of it (observation.py), and what an
instruction's logical form picks out in it (grounding.py -> behaviour.py).

Imports the language room only.
"""
