"""Files and processes: where outputs go and how a run stops.

New-file rules and output sets (:mod:`.paths`), the CSV readers and writers
with their limits (:mod:`.csvfiles`), recordings in MCAP (:mod:`.recording`),
Ctrl-C that keeps finished work (:mod:`.interrupts`) and progress lines
(:mod:`.progress`). It imports only :mod:`slipreflex.core`.
"""
