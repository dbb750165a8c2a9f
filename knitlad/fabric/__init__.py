"""Layer 2, knitted fabric: the scenes that build rods (``scenes/``: the jersey knit, the stitch, rows, a
loop, a rod, a weave), piercing numbers, the observables as functions of positions (``measure.py``), the
affine stretch and force control of a periodic box, the yarn's memory of its shape, the laddering's
observers and stop rules, and the accuracy presets' tables. Imports the engine only."""
