"""knitlad/io/summary.py: the tables' helpers."""


def test_a_point_over_its_knits_is_mean_and_standard_deviation_and_one_run_says_so():
    from knitlad.io.summary import mean_sd

    assert mean_sd([1.0, 2.0, 3.0]) == "2 +- 1" and mean_sd([0.2, float("nan")]) == "0.2 (1 run)"
    assert mean_sd([]) == "-" and mean_sd([0.1, 0.2], "+.1f", ".1f", 100) == "+15.0 +- 7.1"
