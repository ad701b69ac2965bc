"""Writes a Rerun blueprint (layout) for critterbox runs: the world on the left, energy,
collisions and momentum on the right, the timeline following the last step. It is how
docs/viewer.png was made (see docs/viewer.md).

Usage: python3 docs/viewer-blueprint.py OUT.rbl   (needs rerun-sdk==0.36.3)
Then:  rerun RUN.rrd OUT.rbl
"""
import sys

import rerun.blueprint as rrb

bp = rrb.Blueprint(
    rrb.Horizontal(
        rrb.Spatial2DView(origin="/world", name="world"),
        rrb.Vertical(
            rrb.TimeSeriesView(origin="/stats/kinetic_energy", name="kinetic energy"),
            rrb.TimeSeriesView(origin="/stats/collisions", name="collisions"),
            rrb.TimeSeriesView(origin="/stats/momentum", name="momentum"),
        ),
        column_shares=[3, 2],
    ),
    rrb.BlueprintPanel(state="collapsed"),
    rrb.SelectionPanel(state="collapsed"),
    rrb.TimePanel(state="collapsed", timeline="step", play_state="Following"),
)
bp.save("critterbox", sys.argv[1])
