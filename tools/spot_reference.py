"""Independent reference values of a Blender SPOT light's airlight (issue 9 section 3, the strict protocol).

    L_a / I0 = int_0^{D_vp} f(c(x)) w(x) beta e^{-beta (d(x) + x)} / (4 pi d(x)^2) dx

(Sun et al. 2005 Eq. 5 times Blender's spot factor and the Henyey-Greenstein weight), with, at the fog
point x (world position o + x u, p = o + x u - L):

    d = |p|,  w = (1 - g^2) / (1 + g^2 + 2 g p.u / d)^1.5,
    c = -q_z / |q|,  q = inv @ p  (the cosine to the light's local -Z axis, in the light's space),
    f = smoothstep((c - cos_half) / ((1 - cos_half) blend)),  a hard cut (c >= cos_half) at blend = 0.

Nothing here uses fog_addon.  The primary reference (``reference``) is scipy's adaptive quadrature
(QUADPACK QAGS) piece by piece, the ray split at

  * both edges of the cone and of its inner cone (c = cos_half, c = cos_half + (1 - cos_half) blend): the
    roots of the quadratic (q_z)^2 = k^2 |q|^2 in x (q is linear in x), united with the sign changes of
    c - k on a 801-point grid refined by bisection (tests/test_spot.py's reference used 4001 points);
  * the point closest to the light and graded points at h 4^k either side (h the ray's distance to the
    light: the 1/d^2 peak);
  * the extinction scales 4^k / beta;

each piece to epsrel 1e-10.  A ray to the sky (d_vp = inf) is cut at D_sv + 60 / beta (e^{-60} beyond).

The cross-check (``reference_check``) integrates again with a different split and algorithm: QAGP over
the whole ray in one call (epsrel 1e-12), breakpoints from tests/test_spot.py's 4001-point grid bisection
(no quadratic roots), points graded 3^k (not 4^k) about the closest point, and the sky tail by QAGI to
infinity.

``sample_parameters(n, seed)`` draws the strict protocol's samples; the CLI writes the cache

    .venv/bin/python tools/spot_reference.py --n 40000 --processes 2 --out tests/data/spot_reference.npz

g: a tenth of the samples at g = 0, the rest uniform in [-0.8, 0.95] *restricted to N_G values* (one
drawn uniformly in each of N_G equal sub-intervals): the model needs a baked table per g (about 2 s each),
so a continuum of g cannot be tested; N_G = 12 random values cover the range.
"""
import argparse
import math
import multiprocessing as mp
import pathlib
import sys
import time
import warnings

import numpy as np
from scipy import integrate

ROOT = pathlib.Path(__file__).resolve().parents[1]
CACHE = ROOT / "tests" / "data" / "spot_reference.npz"
SEED = 20260923
N_CACHE = 40000
N_G = 12                      # distinct non-zero values of g (each needs its own baked table in the model)
G_RANGE = (-0.8, 0.95)
EPSREL = 1e-10
GRID = 801                    # scan points for the cone edges (plus the analytic roots)
N_CHECK = 200

T_SV = (0.01, 20.0)
T_VP = (0.01, 50.0)
BETA = (1e-3, 1.0)


# --- sampling --------------------------------------------------------------------------------------------

def random_rotation(rng):
    """A uniformly random rotation matrix (from a random unit quaternion)."""
    q = rng.normal(size=4)
    q /= np.linalg.norm(q)
    w, x, y, z = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def _perpendicular(rng, v):
    """A random unit vector perpendicular to unit v."""
    while True:
        r = rng.normal(size=3)
        r -= (r @ v) * v
        n = np.linalg.norm(r)
        if n > 1e-6:
            return r / n


def _aimed_rotation(rng, axis):
    """A rotation R with R @ (0, 0, -1) = unit ``axis`` and a random roll about it."""
    z = -axis
    x = _perpendicular(rng, z)
    y = np.cross(z, x)
    return np.column_stack([x, y, z])


def sample_parameters(n, seed=SEED, n_g=N_G):
    """n random spot-light samples of the strict protocol; a dict of arrays.

    beta log-uniform [1e-3, 1] 1/m; T_sv = beta D_sv log-uniform [0.01, 20]; T_vp log-uniform [0.01, 50],
    a tenth of the rays to the sky (d_vp = inf); light at a random position; cone size uniform 1-180 deg;
    blend uniform 0-1, a fifth exactly 0; light matrix a random rotation, half the time times a
    non-uniform scale diag(U(0.5, 2)^3) (``scaled``); half the orientations uniform, half aimed so that the
    (unscaled) axis points at a random point of the ray's visible part; gamma (the angle between the ray
    and the direction to the light) half the time uniform in [0, size] ("aimed near the light"), half the
    time uniform in (0, pi); g: see the module docstring.
    """
    rng = np.random.default_rng(seed)
    lu = lambda lo, hi: math.exp(rng.uniform(math.log(lo), math.log(hi)))
    lo, hi = G_RANGE
    edges = np.linspace(lo, hi, n_g + 1)
    g_values = np.round(rng.uniform(edges[:-1], edges[1:]), 6)
    out = {k: [] for k in ("beta", "origin", "direction", "light", "inv", "cos_half", "blend", "d_vp", "g",
                           "scaled", "aimed", "near", "size")}
    for _ in range(n):
        beta = lu(*BETA)
        d_sv = lu(*T_SV) / beta
        d_vp = math.inf if rng.uniform() < 0.1 else lu(*T_VP) / beta
        g = 0.0 if rng.uniform() < 0.1 else float(g_values[rng.integers(n_g)])
        size = math.radians(rng.uniform(1.0, 180.0))
        blend = 0.0 if rng.uniform() < 0.2 else rng.uniform(0.0, 1.0)
        light = rng.normal(size=3) * rng.uniform(0.0, 10.0)
        to_viewer = rng.normal(size=3)
        to_viewer /= np.linalg.norm(to_viewer)
        origin = light + d_sv * to_viewer
        near = rng.uniform() < 0.5
        gamma = rng.uniform(0.0, size) if near else rng.uniform(0.0, math.pi)
        gamma = min(max(gamma, 1e-6), math.pi - 1e-6)
        to_light = -to_viewer
        direction = math.cos(gamma) * to_light + math.sin(gamma) * _perpendicular(rng, to_light)
        direction /= np.linalg.norm(direction)
        aimed = rng.uniform() < 0.5
        if aimed:
            reach = d_vp if math.isfinite(d_vp) else d_sv + 3.0 / beta
            target = origin + rng.uniform(0.0, reach) * direction - light
            rot = _aimed_rotation(rng, target / np.linalg.norm(target))
        else:
            rot = random_rotation(rng)
        scaled = rng.uniform() < 0.5
        matrix = rot @ (np.diag(rng.uniform(0.5, 2.0, 3)) if scaled else np.eye(3))
        for k, v in (("beta", beta), ("origin", origin), ("direction", direction), ("light", light),
                     ("inv", np.linalg.inv(matrix)), ("cos_half", math.cos(size / 2)), ("blend", blend),
                     ("d_vp", d_vp), ("g", g), ("scaled", scaled), ("aimed", aimed), ("near", near),
                     ("size", size)):
            out[k].append(v)
    return {k: np.array(v) for k, v in out.items()}


# --- the integrand ----------------------------------------------------------------------------------------

def _falloff(c, cos_half, blend):
    if blend <= 0.0:
        return 1.0 if c >= cos_half else 0.0
    x = min(max((c - cos_half) / ((1.0 - cos_half) * blend), 0.0), 1.0)
    return x * x * (3.0 - 2.0 * x)


class _Ray:
    """The integrand along one ray, with plain floats (fast in scipy's callbacks)."""

    def __init__(self, beta, origin, direction, light, inv, cos_half, blend, g):
        self.beta, self.cos_half, self.blend, self.g = float(beta), float(cos_half), float(blend), float(g)
        p0 = np.asarray(origin, float) - np.asarray(light, float)
        u = np.asarray(direction, float)
        inv = np.asarray(inv, float)
        self.p0 = tuple(map(float, p0))
        self.u = tuple(map(float, u))
        self.q0 = tuple(map(float, inv @ p0))
        self.qu = tuple(map(float, inv @ u))
        self.along = -float(p0 @ u)                      # the point closest to the light
        self.h = float(np.linalg.norm(p0 + self.along * u))
        self.d_sv = float(np.linalg.norm(p0))

    def cosine(self, x):
        qx = self.q0[0] + x * self.qu[0]
        qy = self.q0[1] + x * self.qu[1]
        qz = self.q0[2] + x * self.qu[2]
        n = math.sqrt(qx * qx + qy * qy + qz * qz)
        return -qz / n if n > 0.0 else 1.0

    def __call__(self, x):
        px = self.p0[0] + x * self.u[0]
        py = self.p0[1] + x * self.u[1]
        pz = self.p0[2] + x * self.u[2]
        d2 = px * px + py * py + pz * pz
        if d2 <= 0.0:
            return 0.0
        d = math.sqrt(d2)
        f = _falloff(self.cosine(x), self.cos_half, self.blend)
        if f == 0.0:
            return 0.0
        g = self.g
        w = (1.0 - g * g) / (1.0 + g * g + 2.0 * g * (px * self.u[0] + py * self.u[1] + pz * self.u[2]) / d) ** 1.5 \
            if g else 1.0
        return f * w * self.beta * math.exp(-self.beta * (d + x)) / (4.0 * math.pi * d2)

    # breakpoints
    def quadratic_roots(self, k):
        """x with q_z^2 = k^2 |q|^2 (the cone c = +-k; the wrong sign only adds harmless breakpoints)."""
        q0, qu = np.array(self.q0), np.array(self.qu)
        k2 = k * k
        a = qu[2] ** 2 - k2 * (qu @ qu)
        b = 2.0 * (q0[2] * qu[2] - k2 * (q0 @ qu))
        c = q0[2] ** 2 - k2 * (q0 @ q0)
        if abs(a) < 1e-300:
            return [-c / b] if b != 0.0 else []
        disc = b * b - 4.0 * a * c
        if disc < 0.0:
            return []
        s = math.sqrt(disc)
        q = -0.5 * (b + math.copysign(s, b))
        roots = [q / a]
        if q != 0.0:
            roots.append(c / q)
        return roots

    def scan_roots(self, k, end, n):
        xs = np.linspace(0.0, end, n)
        cs = np.array([self.cosine(x) for x in xs]) - k
        roots = []
        for i in np.nonzero(np.diff(np.sign(cs)))[0]:
            a, b = xs[i], xs[i + 1]
            for _ in range(60):
                mid = 0.5 * (a + b)
                a, b = (mid, b) if (self.cosine(mid) - k) * cs[i] > 0 else (a, mid)
            roots.append(0.5 * (a + b))
        return roots

    def edges_cosines(self):
        return sorted({self.cos_half, self.cos_half + (1.0 - self.cos_half) * self.blend})


def _end(ray, d_vp):
    return d_vp if math.isfinite(d_vp) else ray.d_sv + 60.0 / ray.beta


def reference(beta, origin, direction, light, inv, cos_half, blend, d_vp, g=0.0, epsrel=EPSREL, grid=GRID):
    """The airlight per unit intensity (1/m^2) by scipy quad piece by piece.  Returns (value, est. abs err)."""
    d_vp = float(d_vp)
    if not beta > 0.0 or not d_vp > 0.0:
        return 0.0, 0.0
    ray = _Ray(beta, origin, direction, light, inv, cos_half, blend, g)
    end = _end(ray, d_vp)
    pts = {ray.along}
    for k in ray.edges_cosines():
        pts.update(ray.quadratic_roots(k))
        pts.update(ray.scan_roots(k, end, grid))
    if ray.h > 0.0:
        s = ray.h
        while s < 2.0 * end:
            pts.update((ray.along - s, ray.along + s))
            s *= 4.0
    s = 1.0 / ray.beta / 16.0
    while s < end:
        pts.add(s)
        s *= 4.0
    edges = [0.0, *sorted(p for p in pts if 0.0 < p < end), end]
    total = err = 0.0
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for a, b in zip(edges[:-1], edges[1:]):
            if b > a:
                v, e = integrate.quad(ray, a, b, epsabs=0.0, epsrel=epsrel, limit=400)
                total += v
                err += e
    return total, err


def reference_check(beta, origin, direction, light, inv, cos_half, blend, d_vp, g=0.0):
    """The cross-check: QAGP in one call, another split (see the module docstring), QAGI for the sky."""
    d_vp = float(d_vp)
    if not beta > 0.0 or not d_vp > 0.0:
        return 0.0
    ray = _Ray(beta, origin, direction, light, inv, cos_half, blend, g)
    end = _end(ray, d_vp)
    pts = {ray.along}
    for k in ray.edges_cosines():
        pts.update(ray.scan_roots(k, end, 4001))
    if ray.h > 0.0:
        s = ray.h
        while s < 2.0 * end:
            pts.update((ray.along - s, ray.along + s))
            s *= 3.0
    pts = sorted(p for p in pts if 0.0 < p < end)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        total = 0.0
        # QAGP accepts at most ~ limit breakpoints; chunk them in groups of 40
        bounds = [0.0, *pts, end]
        for i in range(0, len(bounds) - 1, 40):
            a, b = bounds[i], bounds[min(i + 40, len(bounds) - 1)]
            inner = bounds[i + 1:min(i + 40, len(bounds) - 1)]
            total += integrate.quad(ray, a, b, points=inner or None, epsabs=0.0, epsrel=1e-12, limit=2000)[0]
        if not math.isfinite(d_vp):
            total += integrate.quad(ray, end, np.inf, epsabs=0.0, epsrel=1e-12, limit=400)[0]
    return total


# --- the cache --------------------------------------------------------------------------------------------

_S = None


def _init(samples):
    global _S
    _S = samples


def _row(s, i):
    return (s["beta"][i], s["origin"][i], s["direction"][i], s["light"][i], s["inv"][i], s["cos_half"][i],
            s["blend"][i], s["d_vp"][i], s["g"][i])


def _work(i):
    return reference(*_row(_S, i))


def _work_check(i):
    return reference_check(*_row(_S, i))


def build_cache(path=CACHE, n=N_CACHE, seed=SEED, processes=2, n_check=N_CHECK, deadline=None, log=print):
    """Sample, integrate (in ``processes`` workers), cross-check n_check of them, save.

    ``deadline``: a time.time() after which no further chunks are started; the cache then holds the
    samples finished so far (a prefix of the n drawn), and ``n_requested`` records n.
    """
    t0 = time.time()
    s = sample_parameters(n, seed)
    log(f"sampled {n} in {time.time() - t0:.1f} s")
    ref = np.full(n, np.nan)
    est = np.full(n, np.nan)
    done = 0
    chunk = 1000
    ctx = mp.get_context("fork")
    with ctx.Pool(processes, initializer=_init, initargs=(s,)) as pool:
        while done < n:
            if deadline is not None and time.time() > deadline:
                log(f"deadline: stopping after {done} samples")
                break
            idx = range(done, min(done + chunk, n))
            out = pool.map(_work, idx, chunksize=8)
            ref[idx.start:idx.stop] = [o[0] for o in out]
            est[idx.start:idx.stop] = [o[1] for o in out]
            done = idx.stop
            log(f"{done}/{n} in {time.time() - t0:.0f} s")
        rng = np.random.default_rng(seed + 1)
        check_idx = np.sort(rng.choice(done, min(n_check, done), replace=False))
        chk = np.array(pool.map(_work_check, list(check_idx), chunksize=4))
    ref_c = ref[check_idx]
    nz = np.maximum(np.abs(ref_c), np.abs(chk)) > 0
    check_rel = np.zeros(len(check_idx))
    check_rel[nz] = np.abs(chk[nz] - ref_c[nz]) / np.maximum(np.abs(ref_c[nz]), np.abs(chk[nz]))
    est_rel = np.where(ref[:done] > 0, est[:done] / np.where(ref[:done] > 0, ref[:done], 1), 0)
    log(f"{done} references in {time.time() - t0:.1f} s; cross-check on {len(check_idx)}: max rel diff "
        f"{check_rel.max():.2e}; max est. rel err {np.nanmax(est_rel):.2e}; zeros {np.sum(ref[:done] == 0)}")
    path = pathlib.Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    # the inputs are not stored (40 000 of them are 7.5 MB): ``load_cache`` draws them again from the seed
    # and checks them against the first HEAD stored here
    head = {f"head_{k}": v[:HEAD] for k, v in s.items()}
    np.savez_compressed(path, **head, reference=ref[:done], est_abs_err=est[:done], check_index=check_idx,
                        check_value=chk, check_rel_diff=check_rel, check_max_rel_diff=check_rel.max(),
                        seed=seed, n_requested=n, n_g=N_G, epsrel=EPSREL, grid=GRID,
                        seconds=time.time() - t0)
    return load_cache(path)


HEAD = 200   # samples whose inputs the cache stores, to check that ``sample_parameters`` draws the same again


def load_cache(path=CACHE):
    """The cache as a dict: its references with the inputs drawn again by ``sample_parameters`` from its
    seed (about 5 s for 40 000).  Raises ValueError if they differ from the stored first ``HEAD`` (the
    sampler, or numpy's generator, changed: rebuild the cache)."""
    d = dict(np.load(path))
    n = len(d["reference"])
    s = {k: v[:n] for k, v in sample_parameters(int(d["n_requested"]), int(d["seed"]), int(d["n_g"])).items()}
    for k, v in s.items():
        if not np.allclose(v[:HEAD], d[f"head_{k}"], rtol=1e-12, atol=0.0, equal_nan=True):
            raise ValueError(f"{path}: the sampler no longer draws the cached inputs ({k}); rebuild the cache")
    return {**d, **s}


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=N_CACHE)
    ap.add_argument("--seed", type=int, default=SEED)
    ap.add_argument("--processes", type=int, default=2)
    ap.add_argument("--check", type=int, default=N_CHECK, help="samples re-integrated by the cross-check")
    ap.add_argument("--out", default=str(CACHE))
    ap.add_argument("--deadline", default=None,
                    help="UTC HH:MM after which no new chunk of 1000 starts (the cache keeps what is done)")
    a = ap.parse_args()
    deadline = None
    if a.deadline:
        import datetime
        now = datetime.datetime.now(datetime.timezone.utc)
        hh, mm = map(int, a.deadline.split(":"))
        deadline = now.replace(hour=hh, minute=mm, second=0, microsecond=0).timestamp()
    build_cache(a.out, a.n, a.seed, a.processes, a.check, deadline)
    print("wrote", a.out, f"{pathlib.Path(a.out).stat().st_size / 1e6:.2f} MB")
    sys.exit(0)
