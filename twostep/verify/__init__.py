"""Independent plan validation with unified-planning's validator (:mod:`.validation`, on
the environment :mod:`.up_environment` sets up once)."""
