"""Interchangeable agents: one search node for all relabellings of agents with the same plan.

Agents often run plans of the same shape: carts driving their own tracks through the same
hub, helpers doing the same chore on different objects. Swapping two such agents turns
every search node into one with exactly the same future, so the search need only visit
one of them (the orbit of N interchangeable agents has up to N! nodes per index multiset).

Owners and shapes
    A fact's *owners* are the agents whose plans read or write it. A fact with exactly one
    owner is *private* to it: only that agent's actions change it, so its value is a function
    of that agent's plan index (``private_state``). Every other fact is *shared*.
    An agent's *shape* is its plan with the shared facts kept as they are and its private
    facts replaced by what describes them: the (step, role) pairs where the plan uses each,
    its initial value and whether the goal requires it true or false. Two agents with equal shapes are
    *interchangeable*: the map that swaps them and their private facts (each to the other's
    fact with the same uses, initial and goal value) sends every node to a node with the same successors,
    the same interference (only shared facts interfere, and those are the same) and the
    same goal test, so the shortest makespans from both nodes are equal.
    Equal shapes are sufficient, not necessary: a symmetry the numbering misses only costs
    search, never correctness.

Canonical nodes
    Within each class of interchangeable agents the indices are sorted ascending (ties keep
    agent order) and each agent's private facts are set to its new index's private state.
    The result is a real node of the same task, isomorphic to the original, and the
    permutation that leads there is kept so the schedule can be mapped back to the real
    agents (:func:`relabel`).
"""

from __future__ import annotations

from collections.abc import Sequence

from twostep.makespan.compiled import CompiledTask, Node

Permutation = tuple[int, ...]
"""``permutation[agent]``: the agent's label in the canonical node."""


def _bits(mask: int) -> list[int]:
    out = []
    while mask:
        bit = mask & -mask
        out.append(bit)
        mask ^= bit
    return out


class Symmetry:
    """Classes of interchangeable agents of a task, and canonical forms of its nodes."""

    def __init__(self, task: CompiledTask) -> None:
        agents = len(task.steps)
        once = twice = 0
        for mask in task.touched:
            twice |= once & mask
            once |= mask
        private = [mask & ~twice for mask in task.touched]
        self.private = private
        shapes: dict[object, list[int]] = {}
        for agent in range(agents):
            shapes.setdefault(self._shape(task, agent, private[agent]), []).append(agent)
        self.classes: tuple[tuple[int, ...], ...] = tuple(
            tuple(members) for members in shapes.values() if len(members) > 1
        )
        self.class_of: dict[int, int] = {
            agent: number for number, members in enumerate(self.classes) for agent in members
        }
        self.private_in_classes = 0
        for members in self.classes:
            for agent in members:
                self.private_in_classes |= private[agent]
        # private_state[agent][k]: the agent's private facts after its first k actions.
        self.private_state: list[tuple[int, ...]] = []
        for agent in range(agents):
            mask = private[agent]
            state = task.initial & mask
            states = [state]
            for step in task.steps[agent]:
                state = ((state & ~step.delete) | step.add) & mask
                states.append(state)
            self.private_state.append(tuple(states))

    @staticmethod
    def _shape(task: CompiledTask, agent: int, private: int) -> object:
        # A private fact is described by where the plan uses it (step, role) and by its
        # initial and goal values; the plan's private part is then the multiset of these
        # descriptions, whatever numbers the facts happen to have.
        uses: dict[int, list[tuple[int, int]]] = {bit: [] for bit in _bits(private)}
        shared = []
        for k, step in enumerate(task.steps[agent]):
            masks = (step.pre_positive, step.pre_negative, step.add, step.delete)
            shared.append(tuple(mask & ~private for mask in masks))
            for role, mask in enumerate(masks):
                for bit in _bits(mask & private):
                    uses[bit].append((k, role))
        facts = sorted(
            (
                tuple(used),
                bool(task.initial & bit),
                bool(task.goal_positive & bit),
                bool(task.goal_negative & bit),
            )
            for bit, used in uses.items()
        )
        return tuple(shared), tuple(facts)

    def __bool__(self) -> bool:
        return bool(self.classes)

    def canonical(self, node: Node) -> tuple[Node, Permutation | None]:
        """The canonical node of ``node``'s orbit and the relabelling that leads there
        (None when ``node`` is canonical already)."""
        indices, state = node
        permutation: list[int] | None = None
        for members in self.classes:
            order = sorted(members, key=lambda agent: (indices[agent], agent))
            if all(a == b for a, b in zip(order, members, strict=True)):
                continue
            if permutation is None:
                permutation = list(range(len(indices)))
            for label, agent in zip(members, order, strict=True):
                permutation[agent] = label
        if permutation is None:
            return node, None
        moved = [0] * len(indices)
        for agent, label in enumerate(permutation):
            moved[label] = indices[agent]
        state &= ~self.private_in_classes
        for members in self.classes:
            for agent in members:
                state |= self.private_state[agent][moved[agent]]
        return (tuple(moved), state), tuple(permutation)


def relabel(
    agents: int, steps: Sequence[tuple[tuple[int, ...], Permutation | None]]
) -> list[tuple[int, ...]]:
    """The real agents' sets per step from a path of canonical nodes.

    Each path step is (the labels that act in the canonical node, the relabelling applied
    to the child). Real agent r carries label ``label[r]``, starting as itself.
    """
    label = list(range(agents))
    real_of = list(range(agents))
    sets = []
    for chosen, permutation in steps:
        sets.append(tuple(sorted(real_of[a] for a in chosen)))
        if permutation is not None:
            label = [permutation[lab] for lab in label]
            for real, lab in enumerate(label):
                real_of[lab] = real
    return sets
