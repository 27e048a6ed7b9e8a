"""Small shared rules: the checked file reader and atomic writer (:mod:`.files`), secrets
kept out of what is stored or printed (:mod:`.redaction`), the outcome vocabulary: every
status enum and the sets of statuses the rules ask about (:mod:`.outcome`)."""
