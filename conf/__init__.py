"""The ``twostep`` command's Hydra configs, installed as the package ``flows.conf`` (the
app reads them as ``pkg://flows.conf``, from any directory); see ``config.yaml``."""
