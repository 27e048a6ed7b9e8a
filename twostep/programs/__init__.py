"""Fast Downward's programs run as children: where they live (:mod:`.downward`) and the
guard they run under (:mod:`.processes`, with ``_guard.py`` run as a script by path)."""
