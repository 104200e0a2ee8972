"""30-digit summaries of a no-slip history whose extrema lie in delamination next to its branch end
(alpha -> 0), where the engine's locator a folds: delamination followed in alpha instead, with
``mp_model``'s profiles and Newton. Used by the points-independence tests of the large-stretch engine."""
from __future__ import annotations

import mpmath as mp

from tests.reference import mp_model as M

__all__ = ["end_reference", "scene_kwargs"]


def end_reference(control, p, d, w, rs, a_max, n_grid=40):
    """f_max, onset, f_min and turning point of a no-slip history whose extrema lie in delamination
    next to its branch end, to 30 digits (``mp_model``'s profiles and Newton): delamination followed
    in alpha from the onset to 0 (t = sqrt(1 + C2/a^2) from G = w in closed form, the root the onset
    is on; (a, kappa) under pressure control, a under displacement control, from the material
    condition (eq. 61) and the gap); each extremum by Brent about the least grid value, checked
    against pinning's states."""
    pressure = control == "pressure"
    with mp.workdps(M.DPS):
        w, rs, a_max = map(mp.mpf, (w, rs, a_max))
        if pressure:
            d = mp.mpf(d)
            h = M.history("pressure", "no-slip", d=d, w=w, rs=rs, a_max=a_max)
        else:
            p = mp.mpf(p)
            h = M.history("displacement", "no-slip", p=p, w=w, rs=rs, a_max=a_max)
        on = h.onset
        t_on = mp.sqrt(1 + on.C2 / on.a ** 2)

        def roots(al):
            s = mp.sqrt(2 * w - mp.sin(al) ** 2)
            return mp.cos(al) - s, mp.cos(al) + s

        r = roots(on.alpha)
        root = 0 if abs(r[0] - t_on) < abs(r[1] - t_on) else 1
        assert abs(r[root] - t_on) < mp.mpf("1e-20")
        cache = {}

        def solve(al, guess):
            t = roots(al)[root]

            def fun(x):
                kap = x[1] if pressure else p
                sol = M.no_slip_profile(kap, x[0], al, t * t - 1, rs)
                res = [sol.J0 - h.L_m - M.rho_log_ratio(x[0], a_max, rs)]
                if pressure:
                    res.append(sol.gap - d)
                return res, sol
            return M._newton(fun, guess)

        grid = [on.alpha * (1 - mp.mpf(k) / n_grid) for k in range(n_grid)]
        # the last cells toward alpha = 0 graded (the extrema sit within ~1e-5 of it)
        grid += [on.alpha / n_grid * mp.mpf(2) ** -k for k in range(1, 30)] + [mp.mpf(0)]
        sols, x = [on], ([on.a, on.kap] if pressure else [on.a])
        for al in grid[1:]:
            x, sol = solve(al, x)
            sols.append(sol)
            cache[al] = (x, sol)

        def at(al):
            near = min(cache, key=lambda g: abs(g - al))
            x, sol = solve(al, cache[near][0])
            cache[al] = (x, sol)
            return sol

        pin = [h.solve("pinning", on.alpha * mp.mpf(k) / 10) for k in range(10)]
        turn = (lambda s: s.kap) if pressure else (lambda s: -s.gap)
        out = {"f_max": float(h.end.f), "onset": (float(on.f), float(on.kap), float(on.a))}
        for name, obj in (("f_min", lambda s: s.f), ("turning_point", turn)):
            vals = [obj(s) for s in sols]
            i = min(range(len(vals)), key=lambda k: vals[k])
            assert 0 < i, (name, i)
            assert min(obj(s) for s in pin) > vals[i]
            if i == len(grid) - 1:  # the least value at the branch's own end, alpha = 0
                s = sols[i]
                out[name] = (float(s.f), float(s.kap), float(s.a))
                continue
            lo, hi = sorted((grid[i - 1], grid[i + 1]))

            def fun(al, obj=obj):
                return obj(at(al))
            al = M._polish_min(fun, M._brent_min(fun, lo, hi, (hi - lo) * mp.mpf("1e-13")), lo, hi)
            s = at(min([al, lo, hi], key=fun))
            out[name] = (float(s.f), float(s.kap), float(s.a))
        return out


def scene_kwargs(scene):
    kw = {k: v for k, v in scene.items() if k not in ("slip", "lambda0", "p_max", "delta_max")}
    kw.setdefault("p", None)
    kw.setdefault("d", None)
    return kw
