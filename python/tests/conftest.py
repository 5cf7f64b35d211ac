import pytest

# The default grasp without the lift, short: for tests that need a few hundred control ticks with
# contact, not the whole default scenario.
SHORT_GRASP = """name: short_grasp
duration_s: {duration}
object: {{shape: box, size_m: [0.05, 0.05, 0.08], mass_kg: 0.1, friction: 0.8}}
sensor: {{profile: inamp_16bit}}
controller: {{name: grip_slip}}
script:
  - {{at_s: 0.05, action: close}}
expectations:
  not_dropped: true
"""


@pytest.fixture
def short_grasp(tmp_path):
    """Path of a short grasp scenario lasting `duration` seconds (default 0.5)."""
    def make(duration=0.5):
        path = tmp_path / ("short_grasp_%g.yaml" % duration)
        path.write_text(SHORT_GRASP.format(duration=duration))
        return str(path)
    return make
