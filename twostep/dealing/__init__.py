"""plan-deal's algorithm: the SA plan's pieces dealt to N agents, several pieces per agent.

TwoStep gives every helper one subgoal and plans the agents one after the other, so an
agent can only use what the agents before it left behind. On tasks whose work is a chain
of small, similar steps (termes blocks carried up one ramp, barman drinks made in one
shaker) that hand-off caps the overlap: multi-agent PDDL wins there because its agents
take turns on the chain. plan-deal goes beyond TwoStep's single hand-off and lets the
agents take turns on the SA plan itself:

0. *Clean-up* (:mod:`~twostep.dealing.cleanup`): greedy action elimination drops actions
   the goal does not need (a block placed and taken away again). The SA plan itself keeps
   its length in the results; the cleaned length is recorded beside it (``deal`` in
   result.json), and the cleaned plan run by one agent is the one-agent deal.
1. *Order and pieces* (:mod:`~twostep.dealing.deal`), as in
   :mod:`twostep.decomposers.plan_split` (steps 1-2): the deordering of the cleaned plan
   over environment facts (walking left out: it is found again in step 3), and its
   pieces, cut at free agent states (``cut="free"``), tied by what the agent holds
   (``cut="holding"``) or cut at each mover's free states (``cut="mover"``: a robot's
   grippers free, whatever the other robots hold; :mod:`~twostep.dealing.copies`).
2. *Dealing* (:mod:`~twostep.dealing.schedule`): list scheduling of the pieces on N
   agents without the hand-off constraint, at the grain of actions, walks estimated.
3. *Time steps* (:mod:`~twostep.dealing.timeline`): the agents act at once, as in the
   parallel schedule. Each takes the next action of its pieces when the plan's order
   allows it and it applies, else a step of its shortest walk there
   (:mod:`~twostep.dealing.walks`: walks may change shared facts, a hoist leaving an area
   makes it ``clear``), else (where walks change no shared fact) a step towards where it
   will stand for the action, else waits; an idle agent may take a ready piece dealt to another
   (``steal``), and when nobody can act a piece goes to an agent that can reach it. An
   agent that begins a piece may do it with another of its own movers, one that stands
   where the piece begins (:mod:`~twostep.dealing.copies`: each agent has its own copy of
   every robot). When
   that fails (a ramp taken away before an agent crossed it) the deal is made again with
   the walks' causal links kept, and then replayed one piece after the other
   (:mod:`~twostep.dealing.replay`).
4. *Joint clean-up* (:mod:`~twostep.dealing.cleanup`): action elimination again, over the
   run with one copy of the agent facts per agent (detours a single agent needed, walks
   no longer needed, go), and the run's time steps with each action as early as the run
   allows (:func:`~twostep.dealing.timeline.earliest_steps`): the deal's own schedule.

Every action of an agent's plan is an action of Fast Downward's SA plan, or a step of a
walk found by the search of step 3; the joint schedule is re-validated like every other.
The result is deterministic given the SA plan. Facts are bits
(:mod:`~twostep.dealing.encoding`), so that dealing takes about as long as planning the SA
plan, or less. The method that
deals to 1..N agents in each way (:func:`ways`) and keeps the shortest schedule is
:mod:`twostep.methods.plan_deal`.
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
