//! Sites and their maps: upload (map_server YAML + image, or a JSON grid), summary, listing, read-back.

use reqwest::Method;
use reqwest::multipart::{Form, Part};
use shift_proto::{OccupancyGridDoc, SiteList, SiteSummary};

use crate::client::{Client, segment};
use crate::error::{ClientError, Result};

impl Client {
    /// `POST /v1/sites/{site}/map` with a map_server map: the YAML text and the PGM or PNG bytes it names
    /// (`image_name` is only the multipart file name; the daemon ignores the YAML's `image` key). Replaces the
    /// site's map; answers its summary.
    ///
    /// ```no_run
    /// # async fn run() -> shift_client::Result<()> {
    /// # let client = shift_client::Client::new("http://127.0.0.1:7878")?;
    /// let yaml = "image: map.pgm\nresolution: 0.05\norigin: [0.0, 0.0, 0.0]\nnegate: 0\n\
    ///             occupied_thresh: 0.65\nfree_thresh: 0.196\n";
    /// let image = std::fs::read("map.pgm").expect("map image");
    /// let summary = client.upload_map("warehouse", yaml, image, "map.pgm").await?;
    /// println!("{} free cells", summary.free_cells);
    /// # Ok(()) }
    /// ```
    pub async fn upload_map(
        &self,
        site: &str,
        yaml: impl Into<String>,
        image: Vec<u8>,
        image_name: &str,
    ) -> Result<SiteSummary> {
        let mime = if image.starts_with(b"\x89PNG") {
            "image/png"
        } else {
            "image/x-portable-graymap"
        };
        let image = Part::bytes(image)
            .file_name(image_name.to_owned())
            .mime_str(mime)
            .map_err(ClientError::Transport)?;
        let yaml = Part::text(yaml.into())
            .file_name("map.yaml")
            .mime_str("application/yaml")
            .map_err(ClientError::Transport)?;
        let form = Form::new().part("yaml", yaml).part("image", image);
        let path = format!("/v1/sites/{}/map", segment(site));
        self.json(self.request(Method::POST, &path).multipart(form), "the site summary")
            .await
    }

    /// `POST /v1/sites/{site}/map` with a JSON occupancy grid (nav_msgs/OccupancyGrid-shaped).
    ///
    /// ```no_run
    /// # async fn run() -> shift_client::Result<()> {
    /// # let client = shift_client::Client::new("http://127.0.0.1:7878")?;
    /// use shift_client::proto::OccupancyGridDoc;
    /// // A 4 m × 4 m room at 0.1 m with a wall ring.
    /// let (w, h) = (40u64, 40u64);
    /// let cells = (0..w * h)
    ///     .map(|i| {
    ///         let (c, r) = (i % w, i / w);
    ///         if c == 0 || r == 0 || c == w - 1 || r == h - 1 { 100 } else { 0 }
    ///     })
    ///     .collect();
    /// let grid = OccupancyGridDoc {
    ///     resolution: 0.1, origin: [0.0, 0.0], width: w, height: h, cells,
    ///     free_thresh: None, occupied_thresh: None,
    /// };
    /// let summary = client.upload_grid("room", &grid).await?;
    /// assert_eq!(summary.width, 40);
    /// # Ok(()) }
    /// ```
    pub async fn upload_grid(&self, site: &str, grid: &OccupancyGridDoc) -> Result<SiteSummary> {
        let path = format!("/v1/sites/{}/map", segment(site));
        self.json(self.request(Method::POST, &path).json(grid), "the site summary")
            .await
    }

    /// `GET /v1/sites/{site}`: size, resolution, live-map figures.
    ///
    /// ```no_run
    /// # async fn run() -> shift_client::Result<()> {
    /// # let client = shift_client::Client::new("http://127.0.0.1:7878")?;
    /// let site = client.site("demo").await?;
    /// println!("{} × {} cells of {} m", site.width, site.height, site.resolution);
    /// # Ok(()) }
    /// ```
    pub async fn site(&self, site: &str) -> Result<SiteSummary> {
        let path = format!("/v1/sites/{}", segment(site));
        self.json(self.request(Method::GET, &path), "the site summary").await
    }

    /// `GET /v1/sites`: every site, in name order.
    ///
    /// ```no_run
    /// # async fn run() -> shift_client::Result<()> {
    /// # let client = shift_client::Client::new("http://127.0.0.1:7878")?;
    /// for s in client.sites().await?.items {
    ///     println!("{}: {} points in the live map", s.site, s.points_in_tree);
    /// }
    /// # Ok(()) }
    /// ```
    pub async fn sites(&self) -> Result<SiteList> {
        self.json(self.request(Method::GET, "/v1/sites"), "the site list").await
    }

    /// `GET /v1/sites/{site}/map`: the site's thresholded grid (0 free, 100 occupied, −1 unknown).
    ///
    /// ```no_run
    /// # async fn run() -> shift_client::Result<()> {
    /// # let client = shift_client::Client::new("http://127.0.0.1:7878")?;
    /// let grid = client.site_map("demo").await?;
    /// let free = grid.cells.iter().filter(|&&c| c == 0).count();
    /// println!("{free} free cells of {} m", grid.resolution);
    /// # Ok(()) }
    /// ```
    pub async fn site_map(&self, site: &str) -> Result<OccupancyGridDoc> {
        let path = format!("/v1/sites/{}/map", segment(site));
        self.json(self.request(Method::GET, &path), "the site map").await
    }
}
