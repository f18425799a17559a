"""Reading a report page (``gyrofilter report``) as a test must: every tag with its attributes,
the scripts' types and the text of the data block."""
from html.parser import HTMLParser

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
