"""Issue 29: how much of a lamp's glow in a fog layer lies above the layer's top (the add-on keeps it):
quadrature of the single-scattering airlight along camera rays through a homogeneous fog of density beta, with the fog cut at the
top (the truth for a hard top, ignoring that the light reaching the fog above the top crossed less fog) against
uncut (the add-on's kernel).
Run: .venv/bin/python benchmarks/daylight_lamp_top.py (scipy, about a minute); figures in
docs/measurements/2026-11-27-daylight.md.  Smoke mode (``FOG_BENCH_SMOKE=1``, benchmarks/smoke.py): one case, three
ray elevations."""
import numpy as np, math
from scipy import integrate
import smoke
BETAS = smoke.pick((0.02, 0.1), (0.1,))
LAMPS_TOPS = smoke.pick(((5.0, 10.0), (5.0, 20.0), (5.0, 50.0), (9.0, 10.0)), ((5.0, 10.0),))   # (lamp height, top) m
GS = smoke.pick((0.0, 0.7), (0.7,))
ELEVATIONS = np.linspace(-5, 40, smoke.pick(19, 3))   # deg
def glow(cam, d, lamp, beta, top, g=0.0, cut=True, tmax=2000.0):
    def f(t):
        p = cam + t * d
        if cut and p[2] > top:
            return 0.0
        r = lamp - p; dist = np.linalg.norm(r)
        c = np.dot(-r / dist, -d)   # scattering: light travels lamp->p, then p->camera
        ph = (1 - g * g) / (4 * math.pi * (1 + g * g - 2 * g * c) ** 1.5)
        return beta * ph * math.exp(-beta * (t + dist)) / dist ** 2
    return integrate.quad(f, 0, tmax, limit=400, points=[np.dot(lamp - cam, d)])[0]
rows = []
for beta in BETAS:
    for lamp_h, top in LAMPS_TOPS:
        for g in GS:
            lamp = np.array([0.0, 30.0, lamp_h]); cam = np.array([0.0, 0.0, 1.6])
            worst = 0.0; whole = []
            for elev in ELEVATIONS:
                for az in (0.0, 10.0):
                    e, a = math.radians(elev), math.radians(az)
                    d = np.array([math.cos(e) * math.sin(a), math.cos(e) * math.cos(a), math.sin(e)])
                    full = glow(cam, d, lamp, beta, top, g, cut=False); cut = glow(cam, d, lamp, beta, top, g)
                    worst = max(worst, full / cut - 1.0)
            rows.append((beta, lamp_h, top, g, worst))
            print(f"beta {beta} lamp at {lamp_h} m, top {top} m, g {g}: the kept glow above the top adds up to {100*worst:.1f} % on rays from 5 deg below to 40 deg above the horizon", flush=True)
