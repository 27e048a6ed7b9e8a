"""twostep's Hydra plugins: the default launcher and sweeper of a ``twostep -m`` sweep
(:mod:`hydra_plugins.twostep_launcher.twostep_launcher`; the work is in
:mod:`flows.launcher` and :mod:`flows.compose`)."""
