"""The facts and contracts every other layer stands on.

The hardware's numbers (:mod:`.hardware`), the errors (:mod:`.errors`), the
protocols a sample source, a hand and a reflex obey (:mod:`.interfaces`), the
one grip rule (:mod:`.grip`), parameter validation (:mod:`.validation`), the
registry machinery (:mod:`.registry`), the experiments' registered specs
(:mod:`.experiment_specs`) and the taps a run publishes through (:mod:`.taps`).
Nothing here imports another layer of slipreflex.
"""
