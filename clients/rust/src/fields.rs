//! Fields in WGS84: upload a GeoJSON field, plan from a start in lon/lat, read a plan back as GeoJSON.

use reqwest::Method;
use serde_json::Value;
use shift_proto::{FieldRequest, PlanAccepted, PlanRequest, SiteSummary};

use crate::client::{Client, segment};
use crate::error::{ClientError, Result};

impl Client {
    /// `POST /v1/sites/{site}/field`: a field drawn in GeoJSON (`[lon, lat]` degrees; holes and `no_go` polygons
    /// are obstacles) becomes a site whose map frame is a transverse Mercator centred on it; the summary names it
    /// (`crs`, `origin_wgs84`).
    ///
    /// ```no_run
    /// # async fn run() -> shift_client::Result<()> {
    /// # let client = shift_client::Client::new("http://127.0.0.1:7878")?;
    /// use shift_client::proto::FieldRequest;
    /// let field = serde_json::json!({"type": "Polygon", "coordinates": [[
    ///     [8.55, 47.37], [8.553, 47.37], [8.553, 47.372], [8.55, 47.372], [8.55, 47.37]]]});
    /// let request = FieldRequest { field, no_go: vec![], resolution_m: None, tool_width: Some(2.0) };
    /// let site = client.upload_field("north", &request).await?;
    /// println!("{:?} at {:?}", site.crs, site.origin_wgs84);
    /// # Ok(()) }
    /// ```
    pub async fn upload_field(&self, site: &str, request: &FieldRequest) -> Result<SiteSummary> {
        let path = format!("/v1/sites/{}/field", segment(site));
        self.json(self.request(Method::POST, &path).json(request), "the site summary")
            .await
    }

    /// [`Client::create_plan`] with the start given as `[lon, lat]` degrees on a field site (`request.start` is
    /// not sent).
    ///
    /// ```no_run
    /// # async fn run(request: shift_client::proto::PlanRequest) -> shift_client::Result<()> {
    /// # let client = shift_client::Client::new("http://127.0.0.1:7878")?;
    /// let accepted = client.create_plan_wgs84(&request, [8.5502, 47.3702]).await?;
    /// println!("plan {}", accepted.plan_id);
    /// # Ok(()) }
    /// ```
    pub async fn create_plan_wgs84(&self, request: &PlanRequest, start_wgs84: [f64; 2]) -> Result<PlanAccepted> {
        let mut body =
            serde_json::to_value(request).map_err(|e| ClientError::InvalidInput(format!("plan request: {e}")))?;
        if let Some(obj) = body.as_object_mut() {
            obj.remove("start");
            obj.insert("start_wgs84".into(), serde_json::json!(start_wgs84));
        }
        self.json(self.request(Method::POST, "/v1/plans").json(&body), "the accepted plan")
            .await
    }

    /// `GET /v1/plans/{id}/path?crs=wgs84`: a plan on a field site as a GeoJSON Feature (LineString of
    /// `[lon, lat]`; `v`, `t`, `kind` per position in its properties).
    ///
    /// ```no_run
    /// # async fn run() -> shift_client::Result<()> {
    /// # let client = shift_client::Client::new("http://127.0.0.1:7878")?;
    /// let feature = client.path_geojson("p-1").await?;
    /// println!("{}", feature["geometry"]["coordinates"][0]);
    /// # Ok(()) }
    /// ```
    pub async fn path_geojson(&self, plan_id: &str) -> Result<Value> {
        let path = format!("/v1/plans/{}/path?crs=wgs84", segment(plan_id));
        self.json(self.request(Method::GET, &path), "the plan as GeoJSON").await
    }
}
