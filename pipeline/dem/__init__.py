"""What DEM and CFD-DEM codes need from a collision: the wet restitution e(St) in their Stokes-number
conventions (``conventions``), fitted laws (``fits``), the LIGGGHTS contact-law replica and its
calibration (``liggghts``), export files (``export``) and the commands ``ehd export-dem`` and
``ehd restitution`` (``commands``)."""
