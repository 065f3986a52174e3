"""What finished runs say: a sweep's tables, figures and report, confidence intervals over runs, the committed runs
and their provenance, and the results pages' templates."""
