"""The compiler: spec files and instructions in, validated L0-L3 splits, goal DAGs and expert
plans out. Pure Python and numpy (no MuJoCo). Its rooms, lowest first; a room imports only the
rooms below it (and robofollow.errors, resources, files):

    language   instructions <-> logical forms: lexicon, grammar, parser, semantics, realisation
    scene      the benchmark as data and as geometry, and what words pick out in a layout
    authoring  the spec language a task author writes (.rf files) -> the typed benchmark
    planning   behaviour -> goal DAG and expert plan; what the expert can perform
    splits     training tasks checked, L0-L3 test tasks generated and ruled on

`authoring` and `planning` sit side by side: neither imports the other.
"""
