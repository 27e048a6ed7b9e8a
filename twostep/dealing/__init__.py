"""plan-deal's algorithm: the SA plan's pieces dealt to N agents, several pieces per agent.

TwoStep gives every helper one subgoal and plans the agents one after the other, so an
agent can only use what the agents before it left behind. On tasks whose work is a chain
of small, similar steps (termes blocks carried up one ramp, barman drinks made in one
shaker) that hand-off caps the overlap: multi-agent PDDL wins there because its agents
take turns on the chain. plan-deal goes beyond TwoStep's single hand-off and lets the
agents take turns on the SA plan itself:

0. *Clean-up* (:mod:`~twostep.dealing.cleanup`): greedy action elimination drops actions
   the goal does not need (a block placed and taken away again); lama-first's termes
   plans lose up to two thirds. The SA plan itself keeps its length in the results; the
   cleaned length is recorded beside it (``deal`` in result.json).
1. *Order and pieces* (:mod:`~twostep.dealing.deal`), as in
   :mod:`twostep.decomposers.plan_split` (steps 1-2): the deordering of the cleaned plan
   over environment facts (walking left out: it is found again in step 3), and its
   pieces, cut at free agent states (``cut="free"``) or tied by what the agent holds
   (``cut="holding"``).
2. *Dealing* (:mod:`~twostep.dealing.schedule`): list scheduling without the hand-off
   constraint, at the grain of actions.
3. *Agent plans* (:mod:`~twostep.dealing.replay`): the pieces replayed in the order of
   their start times, each by its agent, walking where needed
   (:mod:`~twostep.dealing.walks`). When no walk exists (the walk-free order of step 1
   let a piece take a ramp away before another agent crossed it), the deal is made again
   with the walks' causal links kept.
4. *Joint clean-up* (:mod:`~twostep.dealing.cleanup`): action elimination again, over the
   replay with one copy of the agent facts per agent: detours a single agent needed (a
   block parked on another to free its only arm) go.

Every action of an agent's plan is an action of Fast Downward's SA plan, or a shortest
walk found by the search of step 3; the joint schedule is re-validated like every other.
The result is deterministic given the SA plan. The method that deals with each cut and
order and keeps the shortest schedule is :mod:`twostep.methods.plan_deal`.
"""

from twostep.dealing.cleanup import clean_plan, eliminate_actions, eliminate_joint
from twostep.dealing.deal import CUTS, ORDERS, PHASES, Dealer, Way, deal_plan, ways
from twostep.dealing.model import Deal, DealError

__all__ = [
    "CUTS",
    "ORDERS",
    "PHASES",
    "Deal",
    "DealError",
    "Dealer",
    "Way",
    "clean_plan",
    "deal_plan",
    "eliminate_actions",
    "eliminate_joint",
    "ways",
]
