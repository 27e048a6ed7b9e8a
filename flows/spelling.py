"""Methods by name, and the old spelling that named three of them by ``decomposer``.

``method=plan-deal|portfolio|portfolio-lite`` runs that method; the old spelling,
``method=twostep decomposer=plan-deal``, still runs it for one release, with a one-line
notice (:func:`respell`, :func:`notice`); ``method=twostep`` without a decomposer (whose
default was plan-deal) runs plan-deal as it did, without one (its commands' output stays
as it was; the docs and the changelog say it). The config's default is now
``method: plan-deal`` by name; a decomposer given without a method composes
``method=twostep`` (``conf/decomposer/*.yaml``), as when twostep was the default, and an
option of the default method given the old way, ``decomposer.cut=free`` without a
decomposer, is still read (:func:`_default_options`; silent, as ``method=twostep``
without a decomposer was).

Such a job is *recorded* as the old spelling recorded it (:func:`recorded`): its job key,
its name (``blocksworld-p06-twostep-plan-deal-n2-s0``), its stored ``config.json`` and its
MLflow params are those of ``method=twostep decomposer=<name>`` with the method's options
under ``decomposer``, exactly as before, so a stored result is reused after the rename and
the report groups old and new runs into the same series (result.json's ``method`` is
``twostep`` and its ``decomposer`` the method's name, as the methods always wrote it).
A method added since is recorded under its own name.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

OLD_DEFAULT = "plan-deal"
"""What ``method=twostep`` ran without a decomposer (the old default decomposer)."""
RECORDED_AS_TWOSTEP: dict[str, tuple[str, ...]] = {
    "plan-deal": ("cut", "rebind", "owner_search"),
    "portfolio": ("link_degree", "rebind", "owner_search"),
    "portfolio-lite": ("link_degree", "rebind", "owner_search"),
}
"""The methods the old spelling named by ``decomposer``, and the options it gave them
under ``decomposer`` (now theirs, under ``method``: ``conf/method/<name>.yaml``)."""
METHOD_KEYS = ("name", "fallback_if_longer")  # the method group's keys every method has


def _name(value: Any) -> str | None:
    name = value.get("name") if isinstance(value, Mapping) else value
    return None if name is None else str(name)


def new_spelling(method: str | None, decomposer: str | None) -> str | None:
    """The method an old spelling names (None: ``method``, ``decomposer`` is not one)."""
    if method != "twostep":
        return None
    if decomposer is None:
        return OLD_DEFAULT
    return decomposer if decomposer in RECORDED_AS_TWOSTEP else None


def notice(method: str | None, decomposer: str | None) -> str | None:
    """The one-line notice for an old spelling (None: not one, or ``method=twostep``
    without a decomposer, which says nothing this release)."""
    name = new_spelling(method, decomposer)
    if name is None or decomposer is None:
        return None
    return (
        f"note: method=twostep decomposer={name} is the old spelling of method={name} "
        f"(it still runs, for one more release): write method={name}"
        + (" and method.<option> for decomposer.<option>" if RECORDED_AS_TWOSTEP[name] else "")
    )


def _default_options(method: Any, decomposer: Any) -> dict[str, Any]:
    """The options the old spelling sets under ``decomposer`` for the default method with
    no decomposer (``decomposer.cut=free``, which ``method=twostep`` without a decomposer
    read): those ``decomposer`` sets away from their defaults while ``method`` leaves them
    at theirs (a ``method.cut=...`` given wins)."""
    name = _name(method)
    if _name(decomposer) is not None or name != OLD_DEFAULT:
        return {}
    if not isinstance(method, Mapping) or not isinstance(decomposer, Mapping):
        return {}
    from flows.config import DecomposerConfig

    default = DecomposerConfig()
    return {
        option: decomposer[option]
        for option in RECORDED_AS_TWOSTEP[name]
        if option in decomposer
        and decomposer[option] != getattr(default, option)
        and method.get(option, getattr(default, option)) == getattr(default, option)
    }


def respell(cfg: Any) -> str | None:
    """Rewrite a job's composed config (Hydra's DictConfig) from the old spelling to the new,
    in place: ``method.name`` the method, its options copied from ``decomposer`` to
    ``method`` (``decomposer`` itself is left as it was: :func:`recorded` reads it back).
    Returns the notice (None: the config is in the new spelling)."""
    method, decomposer = _name(cfg.method), _name(cfg.decomposer)
    name = new_spelling(method, decomposer)
    if name is None:
        options = _default_options(cfg.method, cfg.decomposer)
        if options:  # the default method's options given as decomposer.<option>: silent
            from omegaconf import open_dict

            with open_dict(cfg.method):
                for option, value in options.items():
                    cfg.method[option] = value
        return None
    text = notice(method, decomposer)
    from omegaconf import open_dict

    with open_dict(cfg.method):
        cfg.method.name = name
        for option in RECORDED_AS_TWOSTEP[name]:
            if option not in cfg.method:  # method.cut=free beside the old default: kept
                cfg.method[option] = cfg.decomposer[option]
    return text


def respelled(config: Mapping[str, Any]) -> dict[str, Any]:
    """:func:`respell` of a plain config: a new dict, ``config`` untouched."""
    method, decomposer = config.get("method"), config.get("decomposer")
    name = new_spelling(_name(method), _name(decomposer))
    if name is None and isinstance(method, Mapping):
        return {**config, "method": {**method, **_default_options(method, decomposer)}}
    if name is None or not isinstance(method, Mapping):
        return dict(config)
    fields = decomposer if isinstance(decomposer, Mapping) else {}
    options = {k: fields[k] for k in RECORDED_AS_TWOSTEP[name] if k in fields and k not in method}
    return {**config, "method": {**method, "name": name, **options}}


def recorded(config: Mapping[str, Any]) -> dict[str, Any]:
    """A job's plain config (either spelling) as it is recorded (job key, job name, stored
    config, MLflow params): a method of :data:`RECORDED_AS_TWOSTEP` as ``method=twostep
    decomposer=<name>``, its options under ``decomposer``; any other config unchanged."""
    config = respelled(config)
    method = config.get("method")
    name = _name(method)
    if name not in RECORDED_AS_TWOSTEP or not isinstance(method, Mapping):
        return dict(config)
    options = {k: v for k, v in method.items() if k not in METHOD_KEYS}
    decomposer = config.get("decomposer")
    fields = dict(decomposer) if isinstance(decomposer, Mapping) else {}
    return {
        **config,
        "method": {"name": "twostep", "fallback_if_longer": method.get("fallback_if_longer", True)},
        "decomposer": {**fields, "name": name, **options},
    }


def sweep_notice(config: Any) -> str | None:
    """The notice for a sweep (its config: the values it lists, else the one composed) in
    which a job is spelled the old way, said once at its start (None: none is)."""
    from flows.checks import sweep_values

    try:
        values = sweep_values(config)
    except Exception:  # another sweeper's syntax: nothing to say
        return None
    methods = values.get("method", [_name(config.get("method"))])
    decomposers = values.get("decomposer", [_name(config.get("decomposer"))])
    for method in methods:
        for decomposer in decomposers:
            text = notice(None if method is None else str(method),
                          None if decomposer is None else str(decomposer))  # fmt: skip
            if text:
                return text
    return None
