"""A sweep's job configs, composed once per set of config-group choices.

Hydra composes every job of a multirun from scratch (its defaults tree, every YAML file,
the schema merges): 0.1 s per job here, and the basic sweeper does it twice per job (once
to validate the batch, once to launch it). Most jobs of a grid differ from another job
only in plain values (``task=3``, ``seed=1``, ``agents=2``), not in the config groups they
select (``domain=``, ``method=``, ``planner=``). :class:`SweepComposer` composes the first
job of each set of group choices with Hydra itself and derives the others from it: a copy
of that config with the job's plain values applied by Hydra's own override code (the same
``OmegaConf.update`` Hydra runs after composing), and the job's own override list, override
dirname and resolver cache. What stays Hydra's: parsing, the defaults tree, every merge.

A job takes this path only when every one of its overrides is a plain ``key=value`` of a
scalar value on a key that is not a config group; anything else (``+key``, ``~key``, a dict
or list value, a group) is in the key of the cached config or composed in full. The second
job of every group set is also composed in full and compared with the derived one: a
difference (which would be a bug here) turns the shortcut off for that set, with a warning.
"""

from __future__ import annotations

import copy
import sys
from collections import OrderedDict
from dataclasses import dataclass
from typing import Any

from hydra._internal.config_loader_impl import ConfigLoaderImpl, get_overrides_dirname
from hydra.core.config_loader import ConfigLoader
from hydra.core.override_parser.overrides_parser import OverridesParser
from hydra.core.override_parser.types import Override
from omegaconf import DictConfig, OmegaConf, open_dict

SCALARS = (str, int, float, bool, type(None))
CACHE_SIZE = 64  # group sets kept (a grid over 5 domains x 3 methods has 15)


@dataclass
class _Base:
    """The composed config of one group set, and whether the derived configs were checked."""

    config: DictConfig
    checked: bool = False
    trusted: bool = True


def plain_value(override: Override, is_group: bool) -> bool:
    """Whether ``override`` only sets a scalar value (what the shortcut derives)."""
    if is_group or override.is_hydra_override() or override.package is not None:
        return False
    if override.is_delete() or override.is_add() or override.is_force_add():
        return False
    return isinstance(override.value(), SCALARS)


class SweepComposer:
    """Job configs of a sweep from Hydra's config loader (see the module docstring)."""

    def __init__(self, loader: ConfigLoader) -> None:
        self.loader = loader
        self._parser = OverridesParser.create()
        self._bases: OrderedDict[tuple[Any, ...], _Base] = OrderedDict()
        self._groups: dict[str, bool] = {}
        self.full = 0  # compositions by Hydra, for the bench
        self.derived = 0

    def __getstate__(self) -> dict[str, Any]:
        # Sent to each worker process once, with the configs composed (and checked) while
        # the sweeper validated the batch: the workers only derive.
        return {"loader": self.loader, "bases": list(self._bases.items())}

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__init__(state["loader"])  # type: ignore[misc]
        self._bases.update(state["bases"])

    def _is_group(self, key: str) -> bool:
        if key not in self._groups:
            repository = getattr(self.loader, "repository", None)
            exists = repository.group_exists(key) if repository is not None else True
            self._groups[key] = bool(exists)
        return self._groups[key]

    def _signature(
        self, master: DictConfig, overrides: list[Override]
    ) -> tuple[tuple[Any, ...] | None, list[Override]]:
        """The cache key of a job's group set and its plain-value overrides (key None:
        some override needs a full composition)."""
        values: list[Override] = []
        fixed: list[str] = []
        for override in overrides:
            if plain_value(override, self._is_group(override.key_or_group)):
                values.append(override)
            elif override.is_hydra_override() or override.input_line is None:
                return None, []
            else:
                fixed.append(override.input_line)
        hydra_overrides = tuple(str(o) for o in master.hydra.overrides.hydra)
        layout = tuple(
            o.key_or_group if plain_value(o, self._is_group(o.key_or_group)) else "="
            for o in overrides
        )
        return (hydra_overrides, tuple(fixed), layout), values

    def _full(self, master: DictConfig, overrides: list[str]) -> DictConfig:
        self.full += 1
        return self.loader.load_sweep_config(master, overrides)

    def compose(self, master: DictConfig, overrides: list[str]) -> DictConfig:
        """The job's config, equal to Hydra's ``load_sweep_config(master, overrides)``."""
        parsed = self._parser.parse_overrides(overrides)
        key, values = self._signature(master, parsed)
        if key is None:
            return self._full(master, overrides)
        base = self._bases.get(key)
        if base is None:
            config = self._full(master, overrides)
            self._remember(key, _Base(copy.deepcopy(config)))
            return config
        self._bases.move_to_end(key)
        if not base.trusted:
            return self._full(master, overrides)
        derived = self._derive(master, base.config, parsed, values)
        if not base.checked:
            base.checked = True
            full = self._full(master, overrides)
            if _plain(full) != _plain(derived):
                base.trusted = False
                print(
                    "warning: twostep launcher: a derived job config differs from Hydra's "
                    f"({' '.join(overrides)}): composing every job of this group set in full",
                    file=sys.stderr,
                )
                return full
        return derived

    def validate(self, master: DictConfig, overrides: list[str]) -> None:
        """Raise what Hydra would raise composing the job, without keeping a copy of it
        (the sweeper's check of a batch before launching it)."""
        parsed = self._parser.parse_overrides(overrides)
        key, values = self._signature(master, parsed)
        base = self._bases.get(key) if key is not None else None
        if key is None or base is None or not base.trusted or not base.checked:
            self.compose(master, overrides)  # composed in full, or derived and checked
            return
        # The same updates on the cached config itself: every job of the set sets the same
        # keys, so what the cache holds for them is replaced by the next job's values.
        ConfigLoaderImpl._apply_overrides_to_config(values, base.config)

    def _remember(self, key: tuple[Any, ...], base: _Base) -> None:
        self._bases[key] = base
        while len(self._bases) > CACHE_SIZE:
            self._bases.popitem(last=False)

    def _derive(
        self,
        master: DictConfig,
        base: DictConfig,
        parsed: list[Override],
        values: list[Override],
    ) -> DictConfig:
        self.derived += 1
        config = copy.deepcopy(base)
        ConfigLoaderImpl._apply_overrides_to_config(values, config)
        with open_dict(config.hydra):
            config.hydra.overrides.task = [o.input_line for o in parsed]
            job = config.hydra.job
            config.hydra.job.override_dirname = get_overrides_dirname(
                overrides=parsed,
                kv_sep=job.config.override_dirname.kv_sep,
                item_sep=job.config.override_dirname.item_sep,
                exclude_keys=job.config.override_dirname.exclude_keys,
            )
        OmegaConf.copy_cache(from_config=master, to_config=config)
        return config


def _plain(config: DictConfig) -> Any:
    """A config as plain data, interpolations unresolved (what the comparison compares)."""
    return OmegaConf.to_container(config, resolve=False, enum_to_str=True)
