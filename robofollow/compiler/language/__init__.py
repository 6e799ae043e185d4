"""The instruction language: words -> parse tree -> logical form, and back to English.

The lexicon and what it does not cover, the grammar (lark tables), the parser and its
semantics, the typed logical forms (lf.py), their notation and their realisation in several
paraphrase styles. Imports nothing of the compiler: the lowest room.
"""
