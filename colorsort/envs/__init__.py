"""The environments, together: the robosuite task (``robosuite_task.ColorSort``), the Gymnasium env
(``gym_env.ColorSortGymEnv``, one id per variant) and LeRobot's env config (``lerobot_env.ColorSortEnv``,
``--env.type=colorsort``); the observation and action layout they share (``schema``) and the one episode loop
(``rollout``). Above the cell's parts (``colorsort.cell``), below the expert that drives them."""
