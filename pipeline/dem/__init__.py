"""What DEM and CFD-DEM codes need from a collision: the wet restitution e(St) in their Stokes-number
conventions (``conventions``), fitted laws (``fits``), the codes' laws and snippets (``liggghts``:
the replica of LIGGGHTS' contact law and its calibration; ``yade``; ``openfoam``), export files
(``export``) and the commands ``ehd export-dem`` and ``ehd restitution`` (``commands``)."""
