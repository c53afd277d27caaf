"""The live view: the cell in a web page, as its commands run (viser).

``Viewer(sim)`` (:mod:`workcell.view.viewer`) shows a simulator's cell live in a
browser: bodies, collisions in red, the event list, the timeline, the cycle-time report,
jogging (:mod:`workcell.view.jog`) and teaching (:mod:`workcell.view.program`). The
page needs the token in its URL (:mod:`workcell.view.guard`).
"""

from workcell.view.viewer import Viewer

__all__ = ["Viewer"]
