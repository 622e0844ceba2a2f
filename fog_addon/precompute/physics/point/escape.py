"""How much of a light's multiply scattered field the scene's surfaces leave it, numpy only.

Dense Fog's field (``multiple.py``) is that of unbounded fog.  Beside a hood, a wall or the ground, part of the
light's power meets the surface before it scatters and never feeds the field.  Two shares measure it:

* **The escape fraction** f (``escape_fraction``): the share of the emitted power that scatters before it meets a
  surface, over that share in unbounded fog,

      f = int w(u) (1 - e^{-beta D(u)}) du / int w(u) du,

  D(u) the distance to the first surface in direction u, w the light's emission.  It weighs every scattering
  event alike, wherever it is.
* **The second order's share** (``second_order_share``): the field's second order at the points the camera sees,
  with the surfaces stopping the light before its first scattering, over the same without them.  A photon
  scattered first at y (a distance r along u from the light, density beta e^{-beta r}) and then at x adds

      phase(u . (x - y) / |x - y|) e^{-beta |x - y|} / |x - y|^2

  to the fluence at x (radiative transfer in a homogeneous medium, the first scattering's source times the
  point kernel; Narasimhan et al. ``002`` §2 start from the same source).  Summed over the visible points
  ``receivers`` it weighs the sources near what the camera sees: under a hood the fog the camera sees is fed by
  the light going down, and the light stopped above counts less than its share of the power.  Higher orders
  spread farther, towards f; the second order dominates below an optical thickness of about 2.  The second
  flight, from y to x, is judged by ray casts from a few first scatterings (``fog_addon/escape.py``, with
  ``second_order_kernel``): a ray cast per pair would cost 10^6 casts.

Units: positions and distances in m, beta in 1/m; results dimensionless in [0, 1].
"""
import numpy as np

SOURCE_NODES = 12          # first-scattering points along each direction, at equal shares of beta e^{-beta r}
NEAR_FRACTION = 0.25       # a source nearer a receiver than this fraction of the receiver's distance from the light
#                            counts as that far (the quadrature cannot resolve the 1/d^2 spike; both shares alike)
RECEIVER_CHUNK = 32        # receivers at a time (memory: chunk x directions x nodes x 3 floats)


def escape_fraction(beta, depth, weight):
    """f: the emitted power's share (directions weighted by ``weight``, (J,)) that scatters before the first
    surface ``depth`` (J,) m away (inf: none), over unbounded fog's (1).  ``beta`` 1/m."""
    weight = np.asarray(weight, float)
    scattered = -np.expm1(-beta * np.minimum(np.asarray(depth, float), 1e12))
    return float((weight * scattered).sum() / max(weight.sum(), 1e-30))


def second_order_kernel(light, sources, receivers, beta, g, toward=None):
    """(K, S): what a first scattering at each of ``sources`` (S, 3) m, of light from ``light`` (3,), adds to the
    fluence at each of ``receivers`` (K, 3) m (the module docstring's kernel, a source nearer a receiver than
    NEAR_FRACTION of the receiver's distance from the light taken that far).  ``toward``: the sources' unit
    directions from the light (S, 3), if known."""
    light, sources = np.asarray(light, float), np.asarray(sources, float)
    receivers = np.asarray(receivers, float).reshape(-1, 3)
    if toward is None:
        toward = sources - light
        toward = toward / np.maximum(np.linalg.norm(toward, axis=1, keepdims=True), 1e-12)
    u = toward
    v = receivers[:, None, :] - sources[None]
    d2 = np.einsum("ksi,ksi->ks", v, v)
    d = np.sqrt(d2)
    cos = np.einsum("ksi,si->ks", v, u) / np.maximum(d, 1e-12)
    near = NEAR_FRACTION * np.linalg.norm(receivers - light, axis=1)
    return hg_phase(g, cos) * np.exp(-beta * d) / np.maximum(d2, (near * near)[:, None])


def hg_phase(g, cos_theta):
    """Henyey-Greenstein's phase function, 1/sr."""
    return (1.0 - g * g) / (4.0 * np.pi * (1.0 + g * g - 2.0 * g * cos_theta) ** 1.5)


def source_distances(beta, nodes=SOURCE_NODES):
    """(nodes,) m: the distances along a direction where the first scattering is evaluated, each standing for an
    equal share of the density beta e^{-beta r}."""
    return -np.log1p(-(np.arange(nodes) + 0.5) / nodes) / beta


def second_order_share(light, directions, weight, depth, receivers, beta, g, nodes=SOURCE_NODES, with_sources=False):
    """The second order of the field summed over ``receivers`` ((K, 3) m) with the first scattering stopped at
    ``depth`` ((J,) m along the unit ``directions`` (J, 3) from ``light`` (3,), inf: no surface), over the same
    without surfaces.  ``directions`` are about equal solid angles, ``weight`` (J,) the light's emission each way,
    ``g`` the fog's anisotropy.  1 with nothing in the way.  ``with_sources``: (share, the first scatterings'
    points (S, 3) m, what each feeds the receivers' second order (S,), 0 where a surface stopped the light)."""
    light = np.asarray(light, float)
    directions, weight = np.asarray(directions, float), np.asarray(weight, float)
    r = source_distances(beta, nodes)
    lit = (r[None, :] < np.asarray(depth, float)[:, None]).ravel()                # (J n,)
    sources = (light + r[None, :, None] * directions[:, None, :]).reshape(-1, 3)   # (J n, 3)
    toward, emitted = np.repeat(directions, nodes, axis=0), np.repeat(weight, nodes)
    unbounded = 0.0
    feeds = np.zeros(len(sources))
    receivers = np.asarray(receivers, float).reshape(-1, 3)
    for start in range(0, len(receivers), RECEIVER_CHUNK):
        kernel = second_order_kernel(light, sources, receivers[start:start + RECEIVER_CHUNK], beta, g, toward)
        kernel *= emitted[None, :]
        unbounded += float(kernel.sum())
        feeds += (kernel * lit[None]).sum(axis=0)
    occluded = float(feeds.sum())
    share = occluded / unbounded if unbounded > 0.0 else 1.0
    return (share, sources, feeds) if with_sources else share
