"""The identification as a text report."""

from __future__ import annotations

from .result import Identification


def _condition(e: dict) -> str:
    """The condition numbers: the motion's (what ``excite`` reports for a design) and the fitted rows'."""
    fitted = f"{e['fitted_condition_number']:.4g}"
    if e.get("of") != "motion":
        return f"condition number {fitted} (of the fitted rows)"
    return (f"condition number {e['condition_number']:.4g} (of the motion: the regressor at the log's states, as "
            f"excite reports it; of the fitted rows, filtered and weighted: {fitted})")


def format_identification(result: Identification) -> str:
    """The identification as a text report.

    Parameters
    ----------
    result : Identification
        The result of :func:`identify`.

    Returns
    -------
    str
        Header (model, method, samples, condition number), how the standard deviations were
        computed, base parameters (value, std, %sigma, expression), drives and coupled motors
        with their std, residual RMS per joint (training and validation),
        physical check and the notes.
    """
    j = result.to_json()
    n = j["n_samples"]
    removed = ", ".join(f"{v} {k}" for k, v in n["removed"].items()) or "none"
    how = j.get("estimator", j["method"])
    lines = [f"{j['model']}: identification ({how}), {n['used']} samples used of {n['read']} read "
             f"(removed: {removed}); {_condition(j['excitation'])}",
             _excitation_line(j["excitation"]),
             f"standard deviations: {j['covariance']}",
             f"base parameters ({j['convention']} convention, SI units):",
             f"  {'name':<16s} {'value':>14s} {'std':>11s} {'%sigma':>8s}  expression"]
    for b in j["base_parameters"]:
        lines.append(f"  {b['name']:<16s} {b['value']:14.6g} {b['std']:11.3g} {b['pct_sigma']:8.3g}  {b['expression']}")
    if j["drives"]:
        lines.append(f"  {'drives':<16s} {'Ia':>12s} {'Fv':>12s} {'Fc':>12s} {'Fo':>12s}")
        for d in j["drives"]:
            cells = [("-" if d[k] is None else f"{d[k]:.5g}" if not isinstance(d[k], str) else "regrouped")
                     for k in ("Ia", "Fv", "Fc", "Fo")]
            lines.append(f"  {d['joint']:<16s} " + " ".join(f"{c:>12s}" for c in cells))
            if d.get("std"):
                lines.append(f"  {'  std':<16s} " + " ".join(f"{d['std'][k]:>12.3g}" if k in d["std"] else f"{'':>12s}"
                                                         for k in ("Ia", "Fv", "Fc", "Fo")))
    for c in j["couplings"]:
        cells = ", ".join(f"{k} {'-' if c[k] is None else c[k] if isinstance(c[k], str) else f'{c[k]:.5g}'}"
                          + (f" (std {c['std'][k]:.3g})" if k in c.get("std", {}) else "")
                          for k in ("Iam", "Fvm", "Fcm"))
        lines.append(f"  coupled motor {c['name']} (" + ", ".join(f"{w:g} {jn}" for jn, w in c["joints"].items())
                     + f"): {cells}")
    lines += _terms_lines(j.get("terms") or [], fold_unit(j))
    lines += _rms_lines(j) if "currents" not in j else _current_lines(j)
    if j["physical"] is not None:
        p = j["physical"]
        for body, m in p.get("masses_moved", {}).items():
            lines.append(f"physical: body {body} has {m['identified']:.4g} kg, the model file {m['file']:.4g} kg "
                         f"(more than a factor 2 apart): check the file or the excitation")
        lines.append(f"physical: feasible {p['feasible']}, smallest eigenvalue of the N_i {p['min_eigenvalue']:.3g}, "
                     f"solver {p['solver_status']}")
    lines += [f"note: {x}" for x in j["notes"]]
    if j.get("truth") is not None:
        from .saved import format_truth

        lines += ["", format_truth(j["truth"])]
    return "\n".join(lines)


def _excitation_line(e: dict) -> str:
    """``all excited`` only when no direction is weak and every term is well determined."""
    parts = []
    if e["weak"]:
        parts.append(f"POORLY EXCITED (singular values below 1e-3 of the largest): {', '.join(e['weak'])}")
    above = e.get("above_100") or []
    loose = e.get("poorly_determined") or []
    if loose:
        shown = ", ".join(loose[:12]) + (f" and {len(loose) - 12} more" if len(loose) > 12 else "")
        parts.append(f"{len(loose)} term(s) poorly determined (std above their value, inflated by collinearity): "
                     f"{shown}; a richer trajectory (baseparams excite) helps, or a model file whose inertias "
                     "the default estimate can take as its prior")
    if above and not loose and not e["weak"]:
        shown = ", ".join(above[:12]) + (f" and {len(above) - 12} more" if len(above) > 12 else "")
        parts.append(f"{len(above)} term(s) with %sigma above 100 (their std exceeds their value; small terms "
                     f"known to within the noise): {shown}")
    elif above:
        parts.append(f"{len(above)} term(s) in all with %sigma above 100")
    return "excitation: " + ("; ".join(parts) if parts else "every model parameter excited and determined "
                             "(every %sigma at most 100)")


def fold_unit(j: dict) -> str:
    """What the model terms' cross-validation folds were in a result's JSON: ``blocks`` or ``recordings``.

    Several recordings in one identification (the default's rule ``recordings``, or a training score
    per recording: a result of another method, or one read back) take each recording as one fold;
    one log its contiguous blocks.

    Parameters
    ----------
    j : dict
        :meth:`~baseparams.ident.result.Identification.to_json`.

    Returns
    -------
    str
        ``recordings`` or ``blocks`` (:data:`~baseparams.ident.select.FOLD_SCOPES`).
    """
    sel = j.get("selection") or {}
    several = sel.get("rule") == "recordings" or "recordings" in (j.get("train") or {})
    return "recordings" if several else "blocks"


def _terms_lines(terms: list[dict], unit: str = "blocks") -> list[str]:
    """The model terms tried: kept (values), rejected or not tried, with the cross-validated figures."""
    from .select import fold_scope

    if not terms:
        return []
    out = [f"model terms ({fold_scope(unit)}):"]
    for t in terms:
        if t["kept"]:
            out.append(f"  {t['name']:<8s} KEPT      {t['description']} ({t['why']})")
        elif t["why"].startswith("not tried"):
            out.append(f"  {t['name']:<8s} {t['why']}")
        else:
            out.append(f"  {t['name']:<8s} rejected  {t['why']}")
    return out


def _rms_lines(j: dict) -> list[str]:
    """The training and validation RMS lines (one measure: against the raw measured torques)."""
    lines = []
    for label in ("train", "validation"):
        part = j[label]
        if part is None:
            lines.append("validation: none (--holdout SECONDS or --validate FILE)")
            continue
        per = ", ".join(f"{k} {v:.4g}" for k, v in part["rms"].items())
        if label == "train":
            if "samples" in part:
                fit = (f"; on the fit's own rows, filtered and decimated: {part['fit_rms_total']:.4g}"
                       if "fit_rms_total" in part else "")
                lines.append(f"train RMS {part['rms_total']:.4g} against the raw measured torques at every training "
                             f"sample ({part['samples']} samples; per joint: {per}{fit})")
            else:
                lines.append(f"train RMS {part['rms_total']:.4g} (the fit's own rows: filtered and decimated as "
                             f"fitted, not the validation's measure; per joint: {per})")
            continue
        lines.append(f"validation RMS {part['rms_total']:.4g} against the raw measured torques at every held-out "
                     f"sample ({part['samples']} samples, t {part['t_start']:.6g} to {part['t_end']:.6g} s of "
                     f"{part['source']}; per joint: {per})")
        if "score_cutoff" in part:
            per = ", ".join(f"{k} {v:.4g}" for k, v in part["rms_lowpassed"].items())
            lines.append(f"validation RMS {part['rms_lowpassed_total']:.4g} against the measured torques low-passed "
                         f"at {part['score_cutoff']:g} Hz (--score-cutoff; per joint: {per})")
    return lines


def _current_lines(j: dict) -> list[str]:
    """A result from motor currents: the gains, and the RMS of the currents [A] and of any logged joint torques."""
    c = j["currents"]
    lines = [f"gains [N m/A at the joint side] ({c['scale_note'].split(':')[0]}: {c['anchor']}):"]
    anchored = [] if c["anchor"] == "model file" else [a.split("=")[0] for a in c["anchor"].split(",")]
    for m in c["motors"]:
        how = ("anchor" if m in anchored else "NOT DETERMINED" if m in c["undetermined"] else
               f"std {c['std'][m]:.3g}")
        lines.append(f"  {m:<16s} {c['gains'][m]:12.6g}  ({how})")
    for label in ("train", "validation"):
        part = j[label]
        if part is None:
            lines.append("validation: none (--holdout SECONDS or --validate FILE)")
            continue
        what = "training" if label == "train" else "held-out"
        for key, unit, of in (("rms", part.get("unit", "A"), "currents"), ("joint_torque", None, "torques")):
            s = part if key == "rms" else part.get("joint_torque")
            if s is None:
                continue
            per = ", ".join(f"{k} {v:.4g}" for k, v in s["rms"].items())
            lines.append(f"{label} RMS {s['rms_total']:.4g} {unit or s.get('unit', '')} against the raw measured {of} "
                         f"at every {what} sample ({s['samples']} samples; per {'motor' if key == 'rms' else 'joint'}: "
                         f"{per})" + ("; the joint-side torque predicted: rigid body, no motor-side friction or "
                                      "rotor inertia" if key != "rms" else ""))
            if label == "validation" and "score_cutoff" in s:
                lines.append(f"validation RMS {s['rms_lowpassed_total']:.4g} {unit or s.get('unit', '')} against the "
                             f"measured {of} low-passed at {s['score_cutoff']:g} Hz (--score-cutoff)")
    return lines
