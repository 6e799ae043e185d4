"""Evaluating policies over the benchmark. Its rooms, lowest first; a room imports only the
rooms below it (and the layers under robofollow.eval):

    protocols   what a client and a policy server say to each other (wire formats, limits)
    statistics  numbers in, numbers out: cell tables, intervals, paired tests, drops, power
    policies    the policy interface and every way to reach one: reference policies, loading
                by name, the websocket and TCP clients
    running     episodes run and scored, run folders written, resumed, merged, reproduced
    serving     a Python policy served over openpi's websocket or upstream's TCP
    reports     run reports, comparisons of runs, figures, tables and exports

`protocols` and `statistics` sit side by side, as do `policies` and `statistics`, and
`reports` and `serving`.
"""
