"""Serving a Python policy over openpi's websocket or upstream's TCP protocol: one policy
instance per connection, every request checked. Imports policies and protocols; never the
runner.
"""
