"""Dataset configs are validated with the key and line named; sample i is a pure function of
(seed, i); outfits follow the rules; bad references fail before anything renders."""

from __future__ import annotations

import json
from dataclasses import asdict

import numpy as np
import pytest

from avatar.dataset import config, sampling
from avatar.errors import AvatarError, FormatError

BAD = [
    ('seed = "x"', 1, "seed: must be a whole number"),
    ("[camera]\ndistance = [5, 1]", 2, "camera.distance"),
    ("[camera]\ndistanse = 3", 2, "did you mean distance"),
    ('[render]\nengine = "X"', 2, "render.engine"),
    ("count = 0", 1, "count"),
    ('[bodies]\nrig = "nope"', 2, "bodies.rig"),
    ("[people]\ncount = [1.5, 2]", 2, "people.count"),
    ("[bodies]\nage = [0.2, 1.4]", 2, "bodies.age"),
    ('[clothes]\ntops = "tshirt"', 2, "clothes.tops"),
    ("[lights]\nkinds = []", 2, "lights.kinds"),
    ("render = 3", 1, "render: must be a table"),
]


@pytest.mark.parametrize(("text", "line", "message"), BAD)
def test_bad_values_name_the_key_and_line(text, line, message):
    with pytest.raises(FormatError) as err:
        config.loads(text, "bad.toml")
    assert err.value.line == line and message in str(err.value)
    assert str(err.value).startswith(f"bad.toml:{line}: ")


def test_broken_toml_is_a_format_error():
    with pytest.raises(FormatError, match="invalid TOML"):
        config.loads("[render\nx = 1", "bad.toml")


def test_example_config_loads_and_flags_override_it():
    base = config.loads(config.EXAMPLE, "ex.toml")
    assert base.render.resolution == (256, 256) and base.count == 100
    over = config.loads(config.EXAMPLE, "ex.toml", seed=5, count=7, resolution=(64, 48),
                        samples=2)  # fmt: skip
    assert (over.seed, over.count, over.render.resolution, over.render.samples) == \
        (5, 7, (64, 48), 2)  # fmt: skip
    assert over.digest != base.digest  # a resumed run must be the same dataset


def _key(sample: sampling.Sample) -> str:
    data = asdict(sample)
    data["camera"]["camera_to_world"] = np.asarray(sample.camera.camera_to_world).tolist()
    return json.dumps(data, sort_keys=True)


def test_sample_i_is_a_pure_function_of_seed_and_i():
    c = config.loads(config.EXAMPLE)
    forward = [_key(sampling.sample(c, i)) for i in range(20)]
    backward = [_key(sampling.sample(c, i)) for i in reversed(range(20))][::-1]
    assert forward == backward
    assert len(set(forward)) == 20
    other = config.loads(config.EXAMPLE, seed=1)
    assert _key(sampling.sample(other, 3)) != forward[3]


def test_outfits_follow_the_rules():
    c = config.loads(config.EXAMPLE.replace("dress_probability = 0.15", "dress_probability = 0.5"))
    tops, bottoms = set(c.clothes.tops), set(c.clothes.bottoms)
    dresses = 0
    for i in range(200):
        for person in sampling.sample(c, i).people:
            worn = set(person.clothes)
            assert len(worn & tops) <= 1 and len(worn & bottoms) <= 1
            if "dress" in worn:
                dresses += 1
                assert not worn & (tops | bottoms)  # no shirt or trousers under a dress
            else:
                assert len(worn & tops) == 1 and len(worn & bottoms) == 1
            assert {"eyebrows", "eyelashes"} <= worn
    assert 60 < dresses < 140


def test_people_and_bodies_cover_the_ranges():
    c = config.loads(config.EXAMPLE.replace("count = [1, 1]", "count = [1, 3]"))
    counts, ages = set(), []
    for i in range(100):
        s = sampling.sample(c, i)
        counts.add(len(s.people))
        ages += [p.params["age"] for p in s.people]
        for p in s.people:
            mix = [p.params[k] for k in ("african", "asian", "caucasian")]
            assert sum(mix) == pytest.approx(1.0)
    assert counts == {1, 2, 3}
    assert min(ages) < 0.3 and max(ages) > 0.9


@pytest.mark.parametrize(("edit", "message"), [
    ('tops = ["tshirt", "longsleeve"', "tshrt"),
    ('clips = ["walk"]', "no such BVH"),
    ('kinds = ["solid", "procedural"]', "background.folder"),
])  # fmt: skip
def test_bad_references_fail_before_rendering(tmp_path, edit, message):
    text = config.EXAMPLE
    if "tops" in edit:
        text = text.replace(edit, 'tops = ["tshrt", "longsleeve"')
    elif "clips" in edit:
        text = text.replace(edit, f'clips = ["{tmp_path / "missing.bvh"}"]')
    else:
        text = text.replace(edit, 'kinds = ["images"]')
    with pytest.raises(AvatarError, match=message):
        sampling.check(config.loads(text, "ds.toml"))


def test_bvh_clips_and_folders_are_sampled(tmp_path):
    clip = tmp_path / "clips" / "one.bvh"
    clip.parent.mkdir()
    clip.write_text("HIERARCHY\nROOT hips\n{\n OFFSET 0 0 0\n CHANNELS 3 Xrotation Yrotation "
                    "Zrotation\n End Site\n {\n  OFFSET 0 1 0\n }\n}\nMOTION\nFrames: 5\n"
                    "Frame Time: 0.0333\n" + "0 0 0\n" * 5)  # fmt: skip
    text = config.EXAMPLE.replace('clips = ["walk"]', f'clips = ["{clip.parent}"]')
    text = text.replace("pose_probability = 0.2", "pose_probability = 0.0")
    c = config.loads(text)
    sampling.check(c)
    frames = {sampling.sample(c, i).people[0].frame for i in range(40)}
    assert frames <= set(range(5)) and len(frames) > 2
    empty = tmp_path / "empty"
    empty.mkdir()
    with pytest.raises(AvatarError, match="no .bvh files"):
        sampling.check(config.loads(text.replace(str(clip.parent), str(empty))))


def test_population_mode_draws_realistic_statures(model):
    """Population mode: men about 13 cm taller than women on average, adults within the
    surveys' spread, and the height macro hits the drawn stature exactly."""
    from avatar.dataset import population

    rng = np.random.default_rng(0)
    men, women = [], []
    for _ in range(120):
        params = population.draw(rng, model, {})
        years_adult = params["age"] >= population.age_macro(18)
        if years_adult:
            stature = population.stature_of(model, params) * 100
            (men if params["gender"] > 0.5 else women).append(stature)
    assert len(men) > 30 and len(women) > 30
    assert 170 < np.mean(men) < 180 and 157 < np.mean(women) < 167
    assert 8 < np.mean(men) - np.mean(women) < 18
    assert 4 < np.std(men) < 11
    base = {"gender": 0.9, "age": 0.6, "weight": 0.4}
    h = population.height_macro(model, base, 1.83)
    assert population.stature_of(model, base | {"height": h}) == pytest.approx(1.83, abs=1e-3)
    c = config.loads(config.EXAMPLE.replace('mode = "uniform"', 'mode = "population"'))
    assert _key(sampling.sample(c, 4)) == _key(sampling.sample(c, 4))


def test_steady_rate_leaves_out_the_workers_start_up():
    """Two workers: the first two samples carry the workers' start-up; the rate after them
    is the steady one (millions of samples pay the start-up once)."""
    from avatar.dataset.runner import RunReport

    report = RunReport(rendered=6, finished_at=[9.0, 9.5, 11.0, 12.0, 13.5, 14.5])
    assert report.steady_rate(2) == pytest.approx(4 / 5.0)
    assert report.steady_rate(0) == report.steady_rate(1) == pytest.approx(5 / 5.5)
    assert RunReport(finished_at=[3.0]).steady_rate(1) == 0.0
    assert RunReport(finished_at=[1.0, 2.0]).steady_rate(5) == 0.0
