"""What tests share besides fixtures: the conditions under which a test cannot run here,
declared once (:mod:`tests.support.skips`)."""
