"""Many ColorSort cells at once on MuJoCo Warp: the CPU cell's model and rules, N worlds on one device.

Needs the ``gpu`` extra (``pip install -e ".[gpu]"``); only ``colorsort-eval --backend warp`` and
``gym.make_vec(..., vectorization_mode="vector_entry_point")`` import it. docs/gpu.md says what runs where and
what differs from the CPU cell.
"""
