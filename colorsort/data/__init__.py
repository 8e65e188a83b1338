"""Records: the LeRobot schema, the recorder, shards, the on-disk store, replay and video."""
