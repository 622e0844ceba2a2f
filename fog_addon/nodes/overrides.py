"""Cycles settings the fog changes on a material or World while it is on, and gives back exactly.

* A fogged material without emission of its own gets Cycles' emission
  sampling off (``cycles.emission_sampling = 'NONE'``): the fog's emission is
  for camera rays only, and as a light it would steal light samples from the
  lamps (Cycles' light tree counts every emissive mesh; 16 % noise at 1 spp).
* A World of one colour gets no importance map while fogged
  (``cycles.sampling_method = 'NONE'``): with the fog's nodes in it the map
  would be baked on every Cycles render (~2.5 s), and BSDF sampling of a
  constant world loses nothing.

The user's value is kept in the data-block's custom property ``WAS`` (first
override only, so overriding twice keeps the user's value) and put back by
``restore``.
"""
WAS = "analytic_fog_was"   # on a material or World: {"cycles.<setting>": the user's value} the fog changed


def _owner(idblock, path):
    """(the struct holding setting ``path`` of ``idblock``, the setting's name)."""
    owner, _, attr = path.rpartition(".")
    return (idblock.path_resolve(owner) if owner else idblock), attr


def override(idblock, path, value):
    """Set ``idblock``'s setting ``path`` (e.g. "cycles.sampling_method") for the fog, keeping the user's value."""
    owner, attr = _owner(idblock, path)
    was = idblock.get(WAS, {})
    if path not in was:
        was[path] = getattr(owner, attr)
        idblock[WAS] = was
    setattr(owner, attr, value)


def restore(idblock):
    """Give every setting the fog overrode on ``idblock`` back its user's value."""
    for path, value in dict(idblock.get(WAS, {})).items():
        setattr(*_owner(idblock, path), value)
    idblock.pop(WAS, None)
