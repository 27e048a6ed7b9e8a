"""A job's identity (:mod:`.identity`: identity keys, the content-addressed job key, names,
what is stored) and its params as flat dotted names (:mod:`.params`)."""
