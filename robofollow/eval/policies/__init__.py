"""What a policy is and every way to reach one: the interface (policy.py), the reference
policies (expert, blind, noop, random), loading a policy by name, and the clients of openpi's
websocket and upstream's TCP servers. Imports the protocols room only.
"""
