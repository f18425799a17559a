"""Reading a report page (``gyrofilter report``) as a test must: every tag with its attributes,
the scripts' types and the text of the data block; and what every shipped recording's report holds."""
from html.parser import HTMLParser

from gyrofilter.cli import main
from gyrofilter.recording import read_recording
from gyrofilter.view.report import DATA_ID


class Page(HTMLParser):
    """What a self-contained page must be checked for: every tag with its attributes, the
    scripts' types and the text of the data block."""

    def __init__(self):
        super().__init__()
        self.tags, self.scripts, self.data, self._in_data = [], [], None, False

    def handle_starttag(self, tag, attrs):
        attrs = dict(attrs)
        self.tags.append((tag, attrs))
        if tag == "script":
            self.scripts.append(attrs.get("type"))
            self._in_data = attrs.get("id") == DATA_ID

    def handle_endtag(self, tag):
        if tag == "script":
            self._in_data = False

    def handle_data(self, data):
        if self._in_data:
            self.data = (self.data or "") + data


def parse(path):
    page = Page()
    page.feed(open(path, encoding="utf-8").read())
    page.close()
    return page


def check_shipped_report(path, data, capsys):
    """What every shipped recording's report (``data``, of the file ``path``) holds: all its samples, the
    Allan part or its error, the filter's rows or the refusal replay gives, the gap's three axes."""
    rec = read_recording(path)
    assert data["recording"]["samples"] == len(rec)
    assert (data["allan"] is None) == (data["allan_error"] is not None)
    if data["allan"] is None:  # a moving record: allan refuses its gross errors, and the report says so
        assert "gross error" in data["allan_error"] and any("no Allan deviation" in w for w in data["warnings"])
    if data["filter"] is None:  # a record that moves in the start-up window: replay refuses it too
        assert "calibration: the sensor moved" in data["filter_error"]
        assert main(["replay", str(path)]) == 2
        # replay's refusal, its way through (a saved calibration, which report does not take) in report's words
        why, way = data["filter_error"].split("; report filters with the default settings; ")
        replay_said = " ".join(capsys.readouterr().err.split())
        assert " ".join(why.split()) in replay_said and "--calibration FILE" in replay_said
        assert way.startswith("replay and run take a saved calibration (--calibration FILE")
    else:
        assert data["filter"]["rows_out"] > 0
    assert len(data["gap"]["baseline"]["axes"]) == 3
