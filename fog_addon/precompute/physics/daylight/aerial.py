"""The clear air: distance haze (Rayleigh and Mie) and aerial perspective through a fog layer (issue 29).

The air is a function of height only, each species' density e^{-(z - z_ground)/H} over its ground value (flat Earth:
``flat_earth_error`` says where that holds); the kernels take the scalars of ``daylight.py``'s.  Two species of
different scale heights (Rayleigh and Mie, ``haze_airlight``) keep the exponent's identity of ``daylight.py`` (it
holds for the total), so the sum of the two species' integrals is the same closed form; the share of one species
varies along the ray, and it alone is integrated by panels in that species' optical depth, exact in the
exponential's ends.  ``air_glow`` takes the layer and the air together: the sun and the sky reach each point through
both, by panels in which the exponent is linear in each species' optical depth.
"""
import math

from ...core.medium import RAYLEIGH_HEIGHT
from .daylight import (EXP_CLAMP, MIN_FALLOFF, MIN_MU, MIN_SPAN, UNBOUNDED, column_depth, exp_neg, expint2, expint3,
                       extinction, gauss_legendre01, hg_ring_mean, optical_depth, phi1, sky_airlight, sun_integral)

# Distance haze: the clear-sky atmosphere of Bruneton & Neyret 2008 section 2.1 (Eq. 1-4): Rayleigh
# scattering at sea level for lambda = 680, 550, 440 nm, its scale height; aerosols of scale height
# 1.2 km whose extinction is scattering / 0.9; Cornette-Shanks g.
MIE_HEIGHT = 1200.0                          # m (Dobashi et al. 2002 appendix A.1: 1.2 km)
MIE_SCATTERING = 2.0e-5                      # 1/m, a hazy day; a parameter of the kernel
MIE_ALBEDO = 0.9                             # aerosol scattering / extinction
MIE_G = 0.76
EARTH_RADIUS = 6.371e6                       # m (only for the flat-Earth limit, ``flat_earth_error``)
HAZE_PANELS = 12                             # panels of ``haze_airlight``'s Mie integral
HAZE_DEPTH = 20.0                            # a haze ray's panels stop this camera optical depth out
HAZE_HEIGHTS = 8.0                           # ... or this many Mie scale heights above the camera


def haze_grading(panels):
    """The ends of ``haze_airlight``'s panels as fractions of the integrated length: (j / n)^2.5, graded
    towards the camera where the integrand is largest."""
    return tuple((j / panels) ** 2.5 for j in range(panels + 1))


def rayleigh_phase(m, cos_theta):
    """Rayleigh phase function, 1/sr: 3 (1 + cos^2 theta) / (16 pi) (Bruneton & Neyret 2008 Eq. 2)."""
    return (3.0 / (16.0 * math.pi)) * (1.0 + cos_theta * cos_theta)


def cornette_shanks_phase(m, g, cos_theta):
    """Cornette-Shanks phase function, 1/sr (Bruneton & Neyret 2008 Eq. 4, the Mie approximation):
    3 (1 - g^2) (1 + cos^2) / (8 pi (2 + g^2) (1 + g^2 - 2 g cos)^{3/2})."""
    den = 1.0 + g * g - 2.0 * g * cos_theta
    return ((3.0 * (1.0 - g * g)) / (8.0 * math.pi * (2.0 + g * g))) * (1.0 + cos_theta * cos_theta) / (
        den * m.sqrt(den))

# --- distance haze: Rayleigh and Mie (Dobashi et al. 2002 Eq. 11) ----------------------------------------

def haze_extinctions(m, z, z_ground, rayleigh, mie, mie_albedo=MIE_ALBEDO, h_r=RAYLEIGH_HEIGHT,
                     h_m=MIE_HEIGHT):
    """(beta_R, beta_M) at height z (m), 1/m: each species' ground value times e^{-(z - z_ground)/H}
    (Dobashi et al. 2002 appendix A.1's rho_r, rho_m); Rayleigh does not absorb, Mie's extinction is its
    scattering ``mie`` / ``mie_albedo``."""
    y = m.maximum(z - z_ground, 0.0)
    return rayleigh * exp_neg(m, y / h_r), (mie / mie_albedo) * exp_neg(m, y / h_m)


def exponential_depth(m, pz, vz, length, beta_ground, z_ground, H):
    """Optical depth of a segment through one species of density beta_ground e^{-(z - z_ground)/H} (1/m at
    the ground; flat Earth): beta(z_lo) L phi1(|vz| L / H), z_lo the segment's lower end (heights below the
    ground count as the ground).  ``optical_depth`` with h0 = z_ground, in a third of the operations."""
    z_lo = m.minimum(pz, pz + vz * length)
    return beta_ground * exp_neg(m, m.maximum(z_lo - z_ground, 0.0) / H) * length * phi1(m, m.abs(vz) * length / H)


def haze_depth(m, pz, vz, length, z_ground, rayleigh, mie, mie_albedo=MIE_ALBEDO, h_r=RAYLEIGH_HEIGHT,
               h_m=MIE_HEIGHT):
    """Optical depth of a camera segment through both species (Dobashi et al. 2002 Eq. A.1, flat Earth)."""
    return (exponential_depth(m, pz, vz, length, rayleigh, z_ground, h_r)
            + exponential_depth(m, pz, vz, length, mie / mie_albedo, z_ground, h_m))


def haze_sun_depth(m, z, mu_s, z_ground, rayleigh, mie, mie_albedo=MIE_ALBEDO, h_r=RAYLEIGH_HEIGHT,
                   h_m=MIE_HEIGHT):
    """Optical depth from height z (m) to the sun through both species (Dobashi et al. 2002 Eq. A.4's
    exponent, flat Earth): (beta_R(z) H_R + beta_M(z) H_M) / mu_s."""
    br, bm = haze_extinctions(m, z, z_ground, rayleigh, mie, mie_albedo, h_r, h_m)
    return (br * h_r + bm * h_m) / m.maximum(mu_s, MIN_MU)


def haze_airlight(m, pz, vz, length, mu_s, cos_theta, z_ground, rayleigh, mie, mie_albedo=MIE_ALBEDO,
                  g=MIE_G, h_r=RAYLEIGH_HEIGHT, h_m=MIE_HEIGHT, panels=HAZE_PANELS, grading=haze_grading):
    """The sun's single scattering in the haze along a camera segment, per unit sun irradiance (1/sr), one
    colour channel (``rayleigh``: that channel's Rayleigh coefficient at the ground, ``mie``: the aerosols'
    scattering coefficient at the ground, both 1/m): Dobashi et al. 2002 Eq. 11's integral, flat Earth,

        L / E_sun = P_R I_R + P_M a_M I_M,  I_i = int_0^D beta_i(z(t)) e^{-Phi(t)} dt,
        Phi(t) = tau_s(z(t)) + tau_c(t)   (both species),

    P_R Rayleigh, P_M Cornette-Shanks, a_M the aerosols' albedo.  Phi = Phi(0) + k tau_c(t) with
    k = 1 - vz / mu_s holds for each species, hence for their sum, so I_R + I_M = J, the one-species closed
    form of ``sun_integral`` with the total optical depths: exact.  I_M = int e^{-Phi} dtau_M is taken in the
    Mie optical depth tau_M, where Phi is nearly linear (tau_R is a smooth function of tau_M): ``panels``
    panels whose ends are fractions ``grading`` of the integrated length (graded towards the camera), Phi
    exact at their ends and exponential between them (each panel dtau_M e^{-min(Phi_a, Phi_b)}
    phi1(|Phi_b - Phi_a|), the one-species formula).  I_R = J - I_M.  The integrated length stops where the
    camera's optical depth is certainly past HAZE_DEPTH / max(k, 1) (the rest is below e^{-HAZE_DEPTH}
    of what came before) or HAZE_HEIGHTS Mie scale heights above the camera (the aerosols' column left
    is e^{-HAZE_HEIGHTS} of it).  The error of this quadrature is measured against scipy in
    docs/measurements/2026-11-27-daylight-kernels.md."""
    mu = m.maximum(mu_s, MIN_MU)
    k = 1.0 - vz / mu
    beta_m = mie / mie_albedo
    tau_d = haze_depth(m, pz, vz, length, z_ground, rayleigh, mie, mie_albedo, h_r, h_m)
    phi0 = haze_sun_depth(m, pz, mu_s, z_ground, rayleigh, mie, mie_albedo, h_r, h_m)
    phi_d = haze_sun_depth(m, pz + vz * length, mu_s, z_ground, rayleigh, mie, mie_albedo, h_r, h_m) + tau_d
    total = sun_integral(m, tau_d, phi0, phi_d, k)
    br0, bm0 = haze_extinctions(m, pz, z_ground, rayleigh, mie, mie_albedo, h_r, h_m)
    depth = HAZE_DEPTH / m.maximum(k, 1.0)
    up = m.maximum(vz, 0.0)
    # tau_c(t) >= b0 t / (1 + up t / h_m) on a rising ray (each species' 1 - e^{-y} >= y / (1 + y) and
    # h_m <= h_r), >= b0 t on a level or falling one: past t_depth the camera's optical depth exceeds depth
    t_depth = depth / m.maximum((br0 + bm0) - depth * up / h_m, 1e-30)
    t_height = (HAZE_HEIGHTS * h_m) / m.maximum(up, 1e-30)
    t_end = m.minimum(length, m.minimum(t_depth, t_height))
    mie_part = 0.0
    tau_a = phi_a = None
    for s in grading(panels):
        t = t_end * s
        tau_b = exponential_depth(m, pz, vz, t, beta_m, z_ground, h_m)
        phi_b = (haze_sun_depth(m, pz + vz * t, mu_s, z_ground, rayleigh, mie, mie_albedo, h_r, h_m)
                 + exponential_depth(m, pz, vz, t, rayleigh, z_ground, h_r) + tau_b)
        if tau_a is not None:
            mie_part = mie_part + (tau_b - tau_a) * exp_neg(m, m.minimum(phi_a, phi_b)) * phi1(
                m, m.abs(phi_b - phi_a))
        tau_a, phi_a = tau_b, phi_b
    mie_part = m.minimum(mie_part, total)
    out = rayleigh_phase(m, cos_theta) * (total - mie_part) + (
        cornette_shanks_phase(m, g, cos_theta) * mie_albedo) * mie_part
    return m.select(m.less(0.0, mu_s), out, 0.0)


def haze_transmittance(m, pz, vz, length, z_ground, rayleigh, mie, mie_albedo=MIE_ALBEDO,
                       h_r=RAYLEIGH_HEIGHT, h_m=MIE_HEIGHT):
    """e^{-tau} of a camera segment through the haze (Dobashi et al. 2002 Eq. 11's g_v), one channel."""
    return exp_neg(m, haze_depth(m, pz, vz, length, z_ground, rayleigh, mie, mie_albedo, h_r, h_m))


def haze_sun_transmittance(m, z, mu_s, z_ground, rayleigh, mie, mie_albedo=MIE_ALBEDO, h_r=RAYLEIGH_HEIGHT,
                           h_m=MIE_HEIGHT):
    """The fraction of the sun's irradiance that reaches height z through the haze (Dobashi et al. 2002
    Eq. A.4, flat Earth), one channel; 0 for a sun on or below the horizon."""
    t = exp_neg(m, haze_sun_depth(m, z, mu_s, z_ground, rayleigh, mie, mie_albedo, h_r, h_m))
    return m.select(m.less(0.0, mu_s), t, 0.0)


def flat_earth_error(distance, scale_height, earth_radius=EARTH_RADIUS):
    """How much denser the flat-Earth medium is than the round Earth's at the end of a level ray
    ``distance`` m long (a fraction): the ground falls away by d^2 / (2 R), so the true density there is
    e^{-d^2 / (2 R H)} of the flat one's.  Python floats (a design limit, not a kernel)."""
    return math.expm1(distance * distance / (2.0 * earth_radius * scale_height))


# --- the layer in clear air: aerial perspective ----------------------------------------------------------------

AIR_PANELS = 16          # log-spaced panels of ``air_glow``, cut again where the ray crosses the layer:
AIR_CUTS = (0.0, 0.5, 1.0, 2.0, 3.0, 5.0)   # at its top and this many falloff lengths above it (the top if hard)
AIR_FIRST = 0.1          # the first log-spaced panel end: this many mean free paths at the camera


def air_column_depth(m, z, beta_air, h_air):
    """int_z^inf beta_air e^{-z'/h_air} dz' = beta_air h_air e^{-z/h_air}: the clear air's column depth above height
    z (m above the ground, heights below it count as the ground), beta_air its Rayleigh extinction at the ground
    (1/m, one colour channel), h_air its scale height (m; Dobashi et al. 2002 appendix A.1's rho_r)."""
    return beta_air * h_air * exp_neg(m, m.maximum(z, 0.0) / h_air)


def expint4(m, x):
    """E4(x) = int_0^1 mu^2 e^{-x/mu} dmu = (e^{-x} - x E3(x)) / 3 for x >= 0 (E4(0) = 1/3)."""
    return (exp_neg(m, x) - x * expint3(m, x)) * (1.0 / 3.0)


def rayleigh_sky_source(m, c, vz):
    """The uniform sky's Rayleigh single-scattering source per unit sky radiance and unit scattering coefficient
    (1, dimensionless: the radiance scattered towards -v per unit optical depth of air, over L_sky) at a point under
    a column depth c of the layer, for a view direction of z-component vz, ground black:
    int_upper p_R(v.w) e^{-c/mu} dw = 2 pi int_0^1 pbar_R(mu) e^{-c/mu} dmu, the Rayleigh phase averaged over the
    ring at mu being 3 (1 + <(v.w)^2>) / (16 pi) with <(v.w)^2> = mu^2 vz^2 + (1 - mu^2)(1 - vz^2) / 2, so
    = (3 / 8) ((1 + s / 2) E2(c) + (vz^2 - s / 2) E4(c)), s = 1 - vz^2 (``expint2``, ``expint4``)."""
    s = 1.0 - vz * vz
    return (3.0 / 8.0) * ((1.0 + 0.5 * s) * expint2(m, c) + (vz * vz - 0.5 * s) * expint4(m, c))


def _insert_sorted(m, ends, x):
    """The sorted list ``ends`` with x inserted in its place (min and max only)."""
    out = [m.minimum(ends[0], x)]
    out += [m.maximum(ends[i - 1], m.minimum(ends[i], x)) for i in range(1, len(ends))]
    return out + [m.maximum(ends[-1], x)]


def _panel(m, d_a, d_b):
    """int over a panel of e^{-Phi} per unit of a depth in which Phi is linear: e^{-min} phi1(|Phi_b - Phi_a|)."""
    return exp_neg(m, m.minimum(d_a, d_b)) * phi1(m, m.abs(d_b - d_a))


def _air_point(m, pz, vz, t, inv_mu, beta0, h0, H, h_air):
    """``air_glow``'s channel-free quantities at the panel end t: the layer's and the air's (per unit ground extinction)
    optical depths from the camera and their column depths above the point (the air's per unit ground extinction)."""
    z = pz + vz * t
    c_l = column_depth(m, z, beta0, h0, H)
    return (optical_depth(m, pz, vz, t, beta0, h0, H), exponential_depth(m, pz, vz, t, 1.0, 0.0, h_air), c_l,
            air_column_depth(m, z, 1.0, h_air))


def _air_point_hard(m, pz, vz, t, inv_mu, beta0, h0, h_air):
    return _air_point(m, pz, vz, t, inv_mu, beta0, h0, 0.0, h_air)


RATIO_NODES = 6          # Gauss-Legendre sky elevations of ``air_glow``'s layer sky source


def _scaled_source(m, c, vz, rings=None):
    """A sky source times e^{c} (smooth: the panels take e^{-c} with the exponent): the layer's,
    sum_k w_k e^{-c/mu_k} over ``rings`` ((mu_k, w_k): the sky's elevations and weights, the ring-averaged phase
    in them), else the air's Rayleigh source (``rayleigh_sky_source``)."""
    cap = m.minimum(c, EXP_CLAMP)
    if rings is None:
        source = rayleigh_sky_source(m, c, vz)
    else:
        source = 0.0
        for mu, w in rings:
            source = source + w * exp_neg(m, c * (1.0 / mu))
    return source * m.exp(cap)


def layer_sky_rings(m, vz, g, nodes=RATIO_NODES):
    """((mu_k, w_k)): the layer's sky source per unit sky radiance is sum_k w_k e^{-C / mu_k}, w_k the
    Gauss-Legendre weight times 2 pi times the Henyey-Greenstein phase averaged over the ring at mu_k
    (``hg_ring_mean``; 1/2 for isotropic scattering)."""
    xs, ws = gauss_legendre01(nodes)
    return tuple((mu, w * ((2.0 * math.pi) * hg_ring_mean(m, g, mu, vz) if g else 0.5)) for mu, w in zip(xs, ws))


def _air_channel_point(m, b, c_l, c_a, vz, *weights):
    """One channel's quantities at a panel end: the total column C = C_l + b C_a (capped at EXP_CLAMP) and the two
    sky sources over e^{-C} (the layer's, ``weights`` of ``layer_sky_rings`` at its nodes, and the air's)."""
    c = c_l + b * c_a
    rings = tuple(zip(gauss_legendre01(len(weights))[0], weights))
    return m.minimum(c, EXP_CLAMP), _scaled_source(m, c, None, rings), _scaled_source(m, c, vz)


def _air_panel(m, b, inv_mu, la, aa, ca_l, ca_a, xa, ia, ra, lb, ab, cb_l, cb_a, xb, ib, rb):
    """One panel's share of ``air_glow``'s integrals for one channel of air extinction b (1/m at the ground), from
    its ends' depths (layer la, air aa per unit b), columns (ca_l, ca_a), capped total columns (xa) and scaled sky
    sources (isotropic ia, Rayleigh ra): (sun_l, sun_a, sky_a, sky_l)."""
    cam_a, cam_b = la + b * aa, lb + b * ab
    f_sun = _panel(m, (ca_l + b * ca_a) * inv_mu + cam_a, (cb_l + b * cb_a) * inv_mu + cam_b)
    f_sky = _panel(m, xa + cam_a, xb + cam_b)
    d_air, d_layer = b * (ab - aa), lb - la
    return (d_layer * f_sun, d_air * f_sun, (d_air * (0.5 * (ra + rb))) * f_sky, (d_layer * (0.5 * (ia + ib))) * f_sky)


def _layer_sky_panel(m, la, ca, lb, cb, *weights):
    """One panel of the layer's sky glow without air (``air_glow``'s ratio's denominator), from its ends' layer
    depths and columns and the sky's ring weights (``layer_sky_rings``)."""
    rings = tuple(zip(gauss_legendre01(len(weights))[0], weights))
    ia, ib = _scaled_source(m, ca, None, rings), _scaled_source(m, cb, None, rings)
    return ((lb - la) * (0.5 * (ia + ib))) * _panel(m, m.minimum(ca, EXP_CLAMP) + la, m.minimum(cb, EXP_CLAMP) + lb)


def air_glow(m, pz, vz, length, mu_s, beta0, h0, H, air, h_air, g=0.0):
    """Aerial perspective: a camera segment's single-scattering integrals through the fog layer and the clear air,
    per colour channel of ``air`` (the air's Rayleigh extinction at the ground per channel, 1/m): Dobashi et al.
    2002 Eq. 11 with two species, the sun and the sky reaching each point through both (flat Earth),

        sun_l = int beta_l e^{-Psi},  sun_a = int beta_a e^{-Psi},  Psi(t) = (C_l + C_a)(z(t)) / mu_s + tau_l(t)
                                                                           + tau_a(t),
        sky_a = int beta_a S_R(C(z(t)), v_z) e^{-tau_l(t) - tau_a(t)} dt   (``rayleigh_sky_source``),

    and ``sky_ratio``, the air's share of the layer's sky glow: the layer's sky glow with the air (its source under
    C_l + C_a, with the Henyey-Greenstein g's ring means at RATIO_NODES elevations, ``layer_sky_rings``: a forward
    scattering haze sees the sky near the horizon, through long paths of air), dimmed along the segment by both,
    over the same without it; both by the same panels (their errors cancel: 1 at zero air), the latter's rest
    beyond them exact (``sky_airlight``); 1 where the segment meets no layer.  The caller applies it to the layer's
    exact sky glow (any g).  Returns [(sun_l, sun_a, sky_a, sky_ratio)] per channel.

    Quadrature: panels whose ends are AIR_PANELS + 1 log-spaced distances from AIR_FIRST mean free paths at the
    camera to the integrated length, with the crossings of the heights AIR_CUTS falloff lengths above the layer's
    top inserted (the top's alone for a hard top); on each panel the exponent is taken linear in each species'
    optical depth (exact where both are uniform, and for the layer alone: Psi is linear in tau_l without air) and
    a sky source as e^{-C} (with the exponent) times a linear factor.  The integrated length stops where the air
    alone has dimmed the ray by e^{-HAZE_DEPTH}, or HAZE_HEIGHTS air scale heights above the camera (of the air's
    mean channel).  Channel-free quantities are computed once per panel end (node groups: ``_air_point``), the
    channels' per end and per panel (``_air_channel_point``, ``_air_panel``).  Measured against scipy in
    docs/measurements/2026-11-27-air.md."""
    inv_mu = 1.0 / m.maximum(mu_s, MIN_MU)
    air = tuple(air)
    a0 = (air[0] + air[1] + air[2]) * (1.0 / 3.0) * exp_neg(m, m.maximum(pz, 0.0) / h_air)
    up = m.maximum(vz, 0.0)
    t_depth = HAZE_DEPTH / m.maximum(a0 - HAZE_DEPTH * up / h_air, 1e-30)
    t_height = (HAZE_HEIGHTS * h_air) / m.maximum(up, 1e-30)
    t_end = m.minimum(length, m.minimum(t_depth, t_height))
    flat = m.less(m.abs(vz), MIN_SPAN)
    inv_vz = 1.0 / m.select(flat, MIN_SPAN, vz)

    def crossing(h):   # the distance along the ray to height h, in [0, t_end] (t_end for a level ray)
        return m.select(flat, t_end, m.minimum(m.maximum((h - pz) * inv_vz, 0.0), t_end))
    hard = isinstance(H, (int, float)) and H < MIN_FALLOFF
    first = m.maximum(m.minimum(AIR_FIRST / m.maximum(extinction(m, pz, beta0, h0, H) + a0, 1e-30), t_end), 1e-6)
    ratio = 1.0 + t_end / first
    ends = [0.0 * t_end] + [first * (m.power(ratio, j / AIR_PANELS) - 1.0) for j in range(1, AIR_PANELS)] + [t_end]
    for cut in AIR_CUTS[:1] if hard else AIR_CUTS:
        ends = _insert_sorted(m, ends, crossing(h0 + cut * H))
    hard_tag = "hard" if hard else "falloff"
    points = [m.group(f"daylight air point {hard_tag}", _air_point_hard if hard else _air_point, pz, vz, t, inv_mu,
                      beta0, h0, *(() if hard else (H,)), h_air) for t in ends]
    weights = tuple(w for _, w in layer_sky_rings(m, vz, g))
    dry = 0.0
    for pa, pb in zip(points[:-1], points[1:]):
        dry = dry + m.group("daylight air layer sky panel", _layer_sky_panel, pa[0], pa[2], pb[0], pb[2], *weights)
    # beyond the panels' end (where the air has dimmed the ray by e^{-HAZE_DEPTH}) the layer's own glow goes on
    z_end = pz + vz * t_end
    rest = m.maximum(m.minimum(length, UNBOUNDED) - t_end, 0.0)
    tag = f"g {round(float(g) * 10000):+d}e-4"
    dry = dry + exp_neg(m, points[-1][0]) * m.group(
        f"daylight sky {tag}", lambda mm, *a: sky_airlight(mm, *a, albedo=1.0, g=g), z_end, vz, rest, beta0, h0, H)
    has_layer = m.less(1e-30, dry)
    out = []
    for b in air:
        chan = [m.group("daylight air channel point", _air_channel_point, b, p[2], p[3], vz, *weights) for p in points]
        sun_l = sun_a = sky_a = sky_l = 0.0
        for (pa, ca), (pb, cb) in zip(zip(points[:-1], chan[:-1]), zip(points[1:], chan[1:])):
            d = m.group("daylight air panel", _air_panel, b, inv_mu, *pa[:4], *ca, *pb[:4], *cb)
            sun_l, sun_a, sky_a, sky_l = sun_l + d[0], sun_a + d[1], sky_a + d[2], sky_l + d[3]
        out.append((sun_l, sun_a, sky_a, m.select(has_layer, sky_l / m.maximum(dry, 1e-30), 1.0)))
    return out
