"""Navigation: cost, emission and guidance fields, planners, reference states, the event trigger and their participants."""
