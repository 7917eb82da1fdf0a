"""Studies built on the drive: the paper's reproduction (:mod:`imdrive.studies.paper`)."""
