"""The methods: SA PDDL, MA PDDL, TwoStep, plan-deal and the portfolio."""
