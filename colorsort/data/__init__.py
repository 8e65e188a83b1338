"""Records: the recorder, the demonstrator's perturbations, shards, the on-disk store, replay and video. The
LeRobot schema the datasets share with the envs is ``colorsort.envs.schema``."""
