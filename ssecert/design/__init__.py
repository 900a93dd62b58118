"""Observer gains and designs.

``gains`` (pole placement, pseudo-inverse, online gradient) and ``deadbeat`` compute gains and
verify them; ``synthesis`` proposes a gain from the dissipation LMI; ``search`` is the ``ssecert
design`` command's search over a kind's parameters, certifying every candidate as ``analyze``
does (a higher layer than the gains: nothing here imports it).
"""
