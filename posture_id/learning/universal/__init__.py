"""One identifier for every body, every lab PRTS and people-like sway (docs/universal.md).

Layers: :mod:`.scope` (what it is trained on, and drawing it), :mod:`.harmonics` (a
sway's stimulus-locked harmonics, and noise added to them), :mod:`.features` (what the
network sees of one module), :mod:`.data` (the training set), :mod:`.network`,
:mod:`.training`, :mod:`.calibration` and :mod:`.identifier`.
"""
